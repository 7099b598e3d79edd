#!/usr/bin/env python3
"""The cost curve of volume size: nbody and turbulence at growing sizes,
dense and bricked storage, naive and auto, each a whole `lacuna render`
process (load, upload, ranges and build, one timed build and frame after an
untimed one) under /usr/bin/time for its peak host memory. Writes a
Markdown table (OUT.table.md) and an SVG plot (OUT.svg).

    cargo build --release
    python3 bench/scale.py --out docs/results/scale

A size the machine refuses (host memory, device limits) is a row with the
error line: that is a result too.
"""

import argparse
import re
import subprocess
import sys
import time
from pathlib import Path

VOLUMES = ["nbody", "turbulence"]
SIZES = [256, 512, 1024, 2048]
# turbulence:2048 varies everywhere: its pool (1.1x of 8 GiB) passes four
# images of lavapipe's 2 GiB, so it is refused after minutes of generating.
LARGEST = {"nbody": 2048, "turbulence": 1024}
STORAGES = ["dense", "bricks"]
ACCELS = ["naive", "auto"]


def run(binary, volume, storage, accel, size):
    cmd = ["/usr/bin/time", "-v", binary, "render", volume, "--storage", storage,
           "--accel", accel, "--size", f"{size}x{size}", "--filter", "manual",
           # One timed frame and build after an untimed one: lavapipe compiles a
           # kernel over its first frames.
           "--warmup", "1", "--repeat", "1"]
    t = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.monotonic() - t
    out, err = p.stdout, p.stderr
    row = {"wall_s": wall, "ok": p.returncode == 0}
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", err)
    row["peak_gib"] = int(rss.group(1)) / 2**20 if rss else float("nan")
    if not row["ok"]:
        row["error"] = next((l for l in err.splitlines() if l.startswith("error:")), err.strip()[-200:])
        return row
    m = re.search(r"loaded  in (\d+) ms, uploaded in (\d+) ms", out)
    row["load_ms"], row["upload_ms"] = (int(m.group(1)), int(m.group(2))) if m else (None, None)
    m = re.search(r"^storage (.*)$", out, re.M)
    row["storage"] = m.group(1) if m else ""
    m = re.search(r"= ([\d.]+)x dense", row["storage"])
    row["ratio"] = float(m.group(1)) if m else 1.0
    m = re.search(r"^  march\s+([\d.]+) ms", out, re.M)
    row["march_ms"] = float(m.group(1)) if m else None
    # The build's total: the last "total" line before the render passes.
    build = out.split("render GPU time per pass")[0]
    totals = re.findall(r"^  total\s+([\d.]+) ms", build, re.M)
    row["build_ms"] = float(totals[-1]) if totals else 0.0
    return row


def svg(rows, path):
    """Frame time (auto and naive) and pool over dense, against size."""
    w, h, pad = 640, 360, 50
    series = {}
    for (vol, size, storage, accel), r in rows.items():
        if r.get("ok") and r.get("march_ms"):
            series.setdefault(f"{vol} {storage} {accel}", []).append((size, r["march_ms"]))
    import math
    xs = [math.log2(s) for s in SIZES]
    ys = [math.log10(v) for pts in series.values() for _, v in pts] or [0, 1]
    y0, y1 = math.floor(min(ys)), math.ceil(max(ys))
    y1 = max(y1, y0 + 1)
    X = lambda s: pad + (math.log2(s) - xs[0]) / (xs[-1] - xs[0]) * (w - 2 * pad)
    Y = lambda v: h - pad - (math.log10(v) - y0) / (y1 - y0) * (h - 2 * pad)
    colours = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"]
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="11">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<text x="{w/2}" y="18" text-anchor="middle" font-size="13">march time per frame (ms, log) against volume edge</text>']
    for s in SIZES:
        out.append(f'<line x1="{X(s)}" y1="{h-pad}" x2="{X(s)}" y2="{pad}" stroke="#ddd"/>')
        out.append(f'<text x="{X(s)}" y="{h-pad+15}" text-anchor="middle">{s}^3</text>')
    for e in range(y0, y1 + 1):
        out.append(f'<line x1="{pad}" y1="{Y(10**e)}" x2="{w-pad}" y2="{Y(10**e)}" stroke="#ddd"/>')
        out.append(f'<text x="{pad-5}" y="{Y(10**e)+4}" text-anchor="end">{10**e:g}</text>')
    for i, (name, pts) in enumerate(sorted(series.items())):
        c = colours[i % len(colours)]
        dash = ' stroke-dasharray="4 3"' if "bricks" in name else ""
        pts = sorted(pts)
        out.append(f'<polyline fill="none" stroke="{c}" stroke-width="2"{dash} points="'
                   + " ".join(f"{X(s):.1f},{Y(v):.1f}" for s, v in pts) + '"/>')
        out.append(f'<text x="{w-pad+4-160}" y="{pad+14*i}" fill="{c}">{name}</text>')
    out.append("</svg>")
    path.write_text("\n".join(out) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default="target/release/lacuna")
    ap.add_argument("--out", default="docs/results/scale")
    ap.add_argument("--sizes", type=int, nargs="+", default=SIZES)
    a = ap.parse_args()
    rows = {}
    for size in a.sizes:
        for vol in [v for v in VOLUMES if size <= LARGEST[v]]:
            for storage in STORAGES:
                for accel in ACCELS:
                    r = run(a.binary, f"{vol}:{size}", storage, accel, 512)
                    rows[(vol, size, storage, accel)] = r
                    print(vol, size, storage, accel, r, file=sys.stderr, flush=True)
                    if not r["ok"]:
                        break  # the other structure is refused alike
    lines = ["| volume | storage | pool / dense | load s | upload s | naive frame ms | auto build ms | auto frame ms | speed-up | peak host GiB |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for vol in VOLUMES:
        for size in [s for s in a.sizes if s <= LARGEST[vol]]:
            for storage in STORAGES:
                n = rows.get((vol, size, storage, "naive"), {})
                au = rows.get((vol, size, storage, "auto"), {})
                if not n.get("ok"):
                    lines.append(f"| {vol}:{size} | {storage} | {n.get('error', 'not run')} | | | | | | | {n.get('peak_gib', float('nan')):.2f} |")
                    continue
                ratio = f"{n['ratio']:.3f}x" if storage == "bricks" else "1"
                sp = f"{n['march_ms'] / au['march_ms']:.1f}x" if au.get("ok") and au.get("march_ms") else "-"
                peak = max(n["peak_gib"], au.get("peak_gib", 0))
                lines.append(
                    f"| {vol}:{size} | {storage} | {ratio} | {n['load_ms']/1e3:.1f} | {n['upload_ms']/1e3:.1f} | "
                    f"{n['march_ms']:.0f} | {au.get('build_ms', float('nan')):.1f} | {au.get('march_ms') or float('nan'):.1f} | {sp} | {peak:.2f} |")
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".table.md").write_text("\n".join(lines) + "\n")
    svg(rows, out.with_suffix(".svg"))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
