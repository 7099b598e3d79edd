#!/usr/bin/env python3
"""lacuna's auto against VTK's CPU ray caster, interleaved round by round.

compare.py times each side in a block of its own (lacuna's bench run, then
VTK's views), and on this shared VM the two blocks can run at different
speeds: two runs a day apart measured VTK's CPU caster 1.3x to 2x apart
while lacuna moved 1.15x to 1.4x, so the verdict on dense data flipped
between them. This script asks the one question those runs disagreed on,
whether lacuna (auto, the default) beats VTK's CPU caster, in a way the
machine's drift cannot decide:

- Each round times both sides back to back on the same work: `lacuna bench`
  with auto (and naive, which the bench always times first) over the orbit's
  views (two rounds of them, the bench's least), then vtk.py's CPU mapper
  over the same views, or the other way round: the order alternates between
  rounds.
- Per round, each side's median frame (lacuna's over its two rounds of the
  views, VTK's over one); their quotient is that round's speed-up (VTK's
  time over lacuna's). The verdict is the median of
  the rounds' speed-ups, with their min and max: lacuna beats VTK when the
  median is above 1, in every round when the min is.

The work is compare.py's: the same raw files (`lacuna export`), ramps,
512x512 frames, step 0.5, 6 orbit views at elevation 20, and looks:
unshaded composite with early ray termination (VTK's CPU mapper always
terminates early), shaded composite (Blinn-Phong, headlight, ERT on) and
MIP. lacuna's side is the bench's GPU timestamps of the march pass, VTK's
the wall time of Render + glFinish, as in compare.py.

Usage (from the repository root, after `cargo build --release`):
    python3 bench/peers/versus.py [--datasets menger,ch2] [--looks composite,shaded,mip]
        [--rounds 5] [--out docs/results/versus.md] [--quick]
"""

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import compare  # noqa: E402  (this folder's compare.py: export, lacuna_bench, vtk_peer, ...)

ROUND_LOOKS = {
    # look: (page title, ERT on?)
    "composite": ("unshaded composite, ERT on", True),
    "shaded": ("shaded composite, ERT on", True),
    "mip": ("MIP", False),
}


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--lacuna", default=os.path.join(compare.ROOT, "target", "release", "lacuna"))
    p.add_argument("--out", default=os.path.join(compare.ROOT, "docs", "results", "versus.md"))
    p.add_argument("--work", default=os.path.join(compare.ROOT, "bench", "out", "versus"))
    p.add_argument("--datasets", default="menger,ch2",
                   help="comma-separated names from compare.py: nbody,vessels,menger,ch2 (default menger,ch2)")
    p.add_argument("--looks", default="composite,shaded,mip")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--size", default="512x512")
    p.add_argument("--frames", type=int, default=6)
    p.add_argument("--step", type=float, default=0.5)
    p.add_argument("--quick", action="store_true", help="small volumes at 128x128, 2 rounds: checks the script")
    args = p.parse_args(argv)
    names = [d[0] for d in compare.DATASETS]
    args.datasets = [w.strip() for w in args.datasets.split(",") if w.strip()]
    args.looks = [w.strip() for w in args.looks.split(",") if w.strip()]
    bad = [w for w in args.datasets if w not in names] + [w for w in args.looks if w not in ROUND_LOOKS]
    if bad or not args.datasets or not args.looks or args.rounds < 1:
        p.error(f"unknown data set or look {bad}, or no rounds; data sets: {','.join(names)}; "
                f"looks: {','.join(ROUND_LOOKS)}")
    if args.quick:
        args.size, args.frames, args.rounds = "128x128", 2, 2
    return args


def lacuna_round(args, name, raw, tf, look, ert):
    """auto's median frame over the views, each timed twice (the bench's
    least rounds); and what it chose."""
    bench_args = argparse.Namespace(**vars(args))
    bench_args.rounds = 2
    records = compare.lacuna_bench(bench_args, name, raw, tf, ert, look, [("auto", "auto")])
    auto = next(r for r in records if r["structure"] == "auto")
    if auto["error_vs_naive"]["differing"] != 0:
        raise compare.Failure(f"{name} {look}: auto's frame differs from naive's")
    return auto["frame"]["median_ms"], auto.get("chosen")


def vtk_round(args, raw, tf, look, ert, png, coverage):
    """VTK's CPU mapper's median frame over the same views."""
    peer = compare.vtk_peer(args, raw, tf, ert, look, png, coverage, mapper="cpu")
    return peer["mappers"]["cpu"]["median_ms"]


def main(argv):
    args = parse_args(argv)
    if not compare.prerequisites(args.lacuna):
        return 2
    os.makedirs(args.work, exist_ok=True)
    # auto measures its kernel constants once (the first round), then reads them.
    # Mesa's shader cache goes there too: round 1 compiles cold, before the
    # bench's warm-up frames, never in a timed one.
    cache = tempfile.mkdtemp(prefix="versus-cache-")
    os.environ["XDG_CACHE_HOME"] = cache
    try:
        return run_rounds(args)
    finally:
        shutil.rmtree(cache, ignore_errors=True)


def run_rounds(args):
    started = time.monotonic()
    rows = []
    try:
        for name, spec, tf, quick_spec in compare.DATASETS:
            if name not in args.datasets:
                continue
            spec = quick_spec if args.quick else spec
            raw = compare.export(args, name, spec)
            for look in args.looks:
                title, ert = ROUND_LOOKS[look]
                png = os.path.join(args.work, f"{name}-{look}.png")
                compare.lacuna_png(args, raw, tf, ert, look, png)
                coverage = compare.flatten_lacuna_png(png, half=False)
                lac, vtk, chosen = [], [], None
                for r in range(args.rounds):
                    sides = ["lacuna", "vtk"] if r % 2 == 0 else ["vtk", "lacuna"]
                    for side in sides:
                        if side == "lacuna":
                            ms, chosen = lacuna_round(args, name, raw, tf, look, ert)
                            lac.append(ms)
                        else:
                            vtk.append(vtk_round(args, raw, tf, look, ert,
                                                 os.path.join(args.work, f"{name}-{look}-vtk.png"), coverage))
                    print(f"{name} {look} round {r + 1}: lacuna {lac[-1]:.1f} ms, VTK CPU {vtk[-1]:.1f} ms, "
                          f"{vtk[-1] / lac[-1]:.2f}x", file=sys.stderr, flush=True)
                rows.append({"name": name, "spec": spec, "look": title, "lacuna": lac, "vtk": vtk,
                             "ratios": [v / l for l, v in zip(lac, vtk)], "chosen": chosen})
    except compare.Failure as e:
        print(f"error: {e}", file=sys.stderr)
        if rows:
            # What was measured before the failure, marked as partial.
            write_page(args, rows, (time.monotonic() - started) / 60.0, failed=str(e))
            print(f"wrote the finished rows to {args.out}", file=sys.stderr)
        return 1
    minutes = (time.monotonic() - started) / 60.0
    write_page(args, rows, minutes)
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


def write_page(args, rows, minutes, failed=None):
    cmd = "python3 bench/peers/versus.py" + (" --quick" if args.quick else "") + \
        f" --datasets {','.join(args.datasets)} --looks {','.join(args.looks)} --rounds {args.rounds}"
    md = ["# lacuna's auto against VTK's CPU caster, interleaved", "",
          f"Made by `{cmd}` in one run of {minutes:.0f} minutes. Do not edit by hand.", ""]
    if failed:
        md += [f"**Partial**: the run stopped at an error ({failed}); the rows below finished before it.", ""]
    md += [f"{args.size} pixels, step {args.step} voxel, {args.frames} orbit views at elevation 20 (compare.py's "
       "work); per round each side's median frame (lacuna's over two rounds of the views, VTK's over "
       "one), the two timed back to back, the order alternating between rounds (lacuna first in "
       "odd rounds). Speed-up: VTK CPU's time over lacuna's, per round; the verdict is "
       "their median, with the min and max. lacuna: GPU timestamps of the march pass (`lacuna bench`, "
       "auto); VTK: wall time of Render + glFinish (bench/peers/vtk.py, the fixed-point CPU mapper, "
       "which terminates rays early at alpha > 0.992; lacuna's ERT is 0.99).", "",
       "| data set | look | auto chose | lacuna ms (rounds' median) | VTK CPU ms | speed-up, median [min, max] | "
       "lacuna ahead |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        ratios = r["ratios"]
        med = statistics.median(ratios)
        verdict = ("in every round" if min(ratios) > 1.0 else "yes (median)") if med > 1.0 else \
            ("**no**, in no round" if max(ratios) <= 1.0 else "**no** (median)")
        md.append(f"| {r['spec'].split('/')[-1]} | {r['look']} | {r['chosen'] or '-'} | "
                  f"{statistics.median(r['lacuna']):.1f} | {statistics.median(r['vtk']):.1f} | "
                  f"{med:.2f}x [{min(ratios):.2f}, {max(ratios):.2f}] | {verdict} |")
    md += ["", "Per round (lacuna ms / VTK CPU ms):", ""]
    for r in rows:
        rounds = ", ".join(f"{l:.1f} / {v:.1f}" for l, v in zip(r["lacuna"], r["vtk"]))
        md.append(f"- {r['spec'].split('/')[-1]}, {r['look']}: {rounds}")
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    with open(args.out, "w") as f:
        f.write("\n".join(md) + "\n")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
