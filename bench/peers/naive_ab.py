#!/usr/bin/env python3
"""A structure's frame time from two or more lacuna binaries, interleaved.

Measures what changes to the per-sample work bought: run the binaries built
before and after them (A, B, C, ... in the order given) on the same volumes,
transfer functions, cameras and sizes, alternating them every round so
machine load hits all alike, and print a Markdown table of the medians of
the `march` phase (GPU timestamps) with the spread over rounds, and the
last binary's median over A's.

Usage (from the repository root):
    python3 bench/peers/naive_ab.py A_BINARY B_BINARY [C_BINARY ...]
        [--rounds 3] [--b-args "--filter manual"] ... [--accel naive]
        [--cases quick|peers]

Each `--b-args` adds a column running the last binary with those extra
arguments. `--accel` times another structure than naive marching (every
binary must know it); `--cases peers` times the peers' data sets
(bench/peers/compare.py) at 512x512, view 0, ERT on, instead of the quick
ones.
"""

import argparse
import re
import statistics
import subprocess
import sys

CH2 = "/usr/share/mricron/templates/ch2.nii.gz"
# (volume, tf, size, ert): the quick data sets as `lacuna bench --quick`
# frames them, and the ch2 MRI as issue 12 timed it.
CASES = [
    ("nbody:96", None, "256x256", None),
    ("vessels:96", None, "256x256", None),
    ("menger:81", None, "256x256", None),
    ("turbulence:64", None, "256x256", None),
    (CH2, "ramp:0.3:0.6", "512x512", "0.99"),
]
# The peers' data sets, framed as compare.py's view 0.
PEER_CASES = [
    ("nbody:256", None, "512x512", "0.99"),
    ("vessels:192", None, "512x512", "0.99"),
    ("menger:243", None, "512x512", "0.99"),
    (CH2, "ramp:0.3:0.6", "512x512", "0.99"),
]


def march_ms(binary, volume, tf, size, ert, extra, accel, camera):
    cmd = [binary, "render", volume, "--accel", accel, "--size", size, "--repeat", "3", "--warmup", "2",
           "--out", "/tmp/naive_ab.exr"]
    if camera:
        cmd += ["--camera", camera]
    if tf:
        cmd += ["--tf", tf]
    if ert:
        cmd += ["--ert", ert]
    cmd += extra
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed: {p.stderr.strip()}")
    m = re.search(r"^\s*march\s+([0-9.]+) ms", p.stdout, re.M)
    if not m:
        sys.exit(f"no march time in the output of {' '.join(cmd)}")
    return float(m.group(1))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("binaries", nargs="+")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--b-args", action="append", default=[])
    ap.add_argument("--accel", default="naive")
    ap.add_argument("--cases", choices=["quick", "peers"], default="quick")
    args = ap.parse_args()
    cases, camera = (PEER_CASES, "0,20") if args.cases == "peers" else (CASES, None)
    if len(args.binaries) < 2:
        sys.exit("give at least two binaries (before and after)")
    names = [chr(ord("A") + i) for i in range(len(args.binaries))]
    last = names[-1]
    columns = [(n, b, []) for n, b in zip(names, args.binaries)] + [
        (f"{last} {extra}", args.binaries[-1], extra.split()) for extra in args.b_args
    ]
    print("| volume | ERT | " + " | ".join(f"{name} ms" for name, _, _ in columns) + f" | {last} / A |")
    print("|---|---|" + "---|" * len(columns) + "---|")
    for volume, tf, size, ert in cases:
        times = {name: [] for name, _, _ in columns}
        for _ in range(args.rounds):
            for name, binary, extra in columns:
                times[name].append(march_ms(binary, volume, tf, size, ert, extra, args.accel, camera))
        cells = []
        for name, _, _ in columns:
            t = times[name]
            cells.append(f"{statistics.median(t):.1f} [{min(t):.1f}, {max(t):.1f}]")
        ratio = statistics.median(times[last]) / statistics.median(times["A"])
        label = "ch2" if volume == CH2 else volume
        print(f"| {label} {size} | {ert or 'off'} | " + " | ".join(cells) + f" | {ratio:.2f} |", flush=True)


if __name__ == "__main__":
    main()
