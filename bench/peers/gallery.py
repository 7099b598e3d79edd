#!/usr/bin/env python3
"""The looks gallery: every lacuna mode beside VTK's image of the same work.

Writes docs/gallery.md and docs/gallery/*.png: each of lacuna's looks
(composite, composite shaded, MIP, MinIP, average, iso) on the ch2 brain MRI
and on generated volumes, and two channels (the MRI and a channel derived
from it, its gradient magnitude, each with its own transfer function), 256x256 over black, beside VTK's image of the same
raw file, camera, transfer function and look (bench/peers/vtk.py: the fixed-
point CPU mapper where it has the mode, else the GPU mapper, labelled), or a
note where VTK has no such mode. Under each pair: both sides' visible pixels,
the mean difference where either side shows something, and one line on what
differs to the eye (NOTES below, written from looking at the images).

Usage (from the repository root, after `cargo build --release`):
    python3 bench/peers/gallery.py [--lacuna target/release/lacuna]
        [--out docs/gallery.md] [--work bench/out/gallery] [--size 256x256]

A minute or two on two cores. Requirements as bench/peers/compare.py's: a
release build of lacuna, `pip install vtk numpy`, `apt install libosmesa6`,
and Debian's mricron-data for the ch2 MRI.
"""

import argparse
import json
import os
import shlex
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
CH2 = "/usr/share/mricron/templates/ch2.nii.gz"
CAMERA = (0.0, 20.0)  # azimuth, elevation: view 0 of the bench orbit, as docs/results/peers.md
CPU, GPU = "cpu", "gpu"
# Two channels: the MRI joined with a channel derived from it (`derive_edges`).
TWO = "ch2+edges"
TWO_TFS = ["bench/peers/tf/ch2-tissue.json", "bench/peers/tf/ch2-edges.json"]
MAPPER_LABEL = {CPU: "VTK CPU (fixed point)", GPU: "VTK GPU (llvmpipe)"}

# Volumes: (key, title, spec).
VOLUMES = [
    ("ch2", "ch2 brain MRI (`/usr/share/mricron/templates/ch2.nii.gz`)", CH2),
    (TWO, "two channels: the ch2 MRI and its gradient magnitude (`ch2.raw+ch2-edges.raw`)", None),
    ("vessels", "generated vessels (`vessels:128`)", "vessels:128"),
    ("turbulence", "generated turbulence (`turbulence:128`)", "turbulence:128"),
]
# Rows: (volume key, row key, title, tf, lacuna look args, VTK mapper or None
# with the reason VTK has no such mode). vtk.py takes the same look args.
# MinIP needs rays that see no background (lacuna and VTK both take the
# smallest sample, and air is 0): the ch2 rows crop to the inside of the
# head; vessels' background is 0 on every ray, so its MinIP row is the
# turbulence noise field cropped to a slab. Average rows use a low ramp
# (the mean along a ray is far below the tissue values).
NO_AVERAGE = ("VTK has no such mode: its AVERAGE_INTENSITY_BLEND is an opacity-weighted mean shown "
              "as opaque grey, not lacuna's mean sample through the TF")
ROWS = [
    ("ch2", "composite", "composite", "ramp:0.3:0.6", [], CPU),
    ("ch2", "shaded", "composite, shaded", "ramp:0.3:0.6", ["--shade", "on"], CPU),
    ("ch2", "mip", "MIP", "ramp:0.3:0.6", ["--mode", "mip"], CPU),
    ("ch2", "minip", "MinIP, cropped to x 40:141, y 50:170, z 60:120", "ramp:0.1:0.5",
     ["--mode", "minip", "--crop", "40:141,50:170,60:120"], CPU),
    ("ch2", "average", "average", "ramp:0.05:0.4", ["--mode", "average"], NO_AVERAGE),
    ("ch2", "iso", "iso 0.45", "ramp:0.3:0.6", ["--mode", "iso", "--iso", "0.45"], GPU),
    (TWO, "composite", "composite, cropped to z 0:90", TWO_TFS, ["--crop", "0:181,0:217,0:90"], CPU),
    ("vessels", "composite", "composite", "ramp:0.3:1", [], CPU),
    ("vessels", "shaded", "composite, shaded", "ramp:0.3:1", ["--shade", "on"], CPU),
    ("vessels", "mip", "MIP", "ramp:0.3:1", ["--mode", "mip"], CPU),
    ("vessels", "average", "average", "ramp:0:0.08", ["--mode", "average"], NO_AVERAGE),
    ("vessels", "iso", "iso 0.3", "ramp:0.3:1", ["--mode", "iso", "--iso", "0.3"], GPU),
    ("turbulence", "minip", "MinIP, cropped to the slab z 56:72", "ramp:0:0.4",
     ["--mode", "minip", "--crop", "0:128,0:128,56:72"], CPU),
]
# What differs to the eye, per row (from looking at the images; the numbers
# beside them are measured on every run).
NOTES = {
    ("ch2", "composite"): "Alike; VTK CPU adds a faint rim of about one pixel round the head.",
    ("ch2", "shaded"): "Alike; VTK CPU's scalp is a little softer (it lights quantised per-voxel normals and "
    "interpolates the lit colours), lacuna's fine ridges a little crisper.",
    ("ch2", "mip"): "Alike, the same bright fat and vessels; VTK CPU slightly softer at the rim.",
    ("ch2", "minip"): "Alike: the same ventricles and sulci inside the same crop box.",
    ("ch2", "average"): "",
    ("ch2", "iso"): "Same surface, with the same few holes where the bright scalp layer has gaps (the brain "
    "itself lies below 0.45, so those rays cross nothing); VTK "
    "GPU's highlight is a tighter, glossier spot (Phong's (R.V)^n against lacuna's Blinn (N.H)^n) and its "
    "surface a little more faceted (no refinement of the crossing).",
    ("vessels", "composite"): "Alike in colour; VTK CPU draws every vessel slightly wider with a faint halo "
    "(about 4 % more visible pixels, mean 36/255 there); its GPU mapper matches lacuna to within 1/255 on "
    "average, so the framing and TF are right and the halo is the fixed-point mapper's own.",
    ("vessels", "shaded"): "Alike in shading; the same wider, softer vessels on VTK CPU as unshaded.",
    ("vessels", "mip"): "Alike; VTK CPU's vessels again slightly wider with a faint halo.",
    ("vessels", "average"): "",
    (TWO, "composite"): "Alike: warm tissue with cyan boundaries, the same ventricles and sulci; VTK's "
    "independent components give the scalp's rim a brighter, crisper edge.",
    ("vessels", "iso"): "Same tubes; VTK GPU's highlights are narrower and glossier (Phong against "
    "Blinn), lacuna's surfaces a touch smoother.",
    ("turbulence", "minip"): "Alike, blob for blob inside the slab.",
}


class Failure(Exception):
    pass


def run(cmd):
    print("$ " + " ".join(shlex.quote(c) for c in cmd), file=sys.stderr)
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if p.returncode != 0:
        last = (p.stderr or "").strip().splitlines()[-1:] or ["(no message)"]
        raise Failure(f"{os.path.basename(cmd[0])} {cmd[1] if len(cmd) > 1 else ''} failed: {last[0]}")
    return p.stdout


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--lacuna", default=os.path.join(ROOT, "target", "release", "lacuna"))
    p.add_argument("--out", default=os.path.join(ROOT, "docs", "gallery.md"))
    p.add_argument("--work", default=os.path.join(ROOT, "bench", "out", "gallery"))
    p.add_argument("--size", default="256x256")
    return p.parse_args(argv)


def read_rgb(path):
    """An 8-bit PNG's RGB as a numpy array (sRGB values 0..255)."""
    from compare import read_png

    np, a = read_png(path)
    return np, a[..., :3] * 255.0


def compare(lacuna_png, vtk_png):
    """(lacuna coverage, VTK coverage, mean |difference| of sRGB channels where
    either side shows something, on 0..255)."""
    np, a = read_rgb(lacuna_png)
    _, b = read_rgb(vtk_png)
    va = a.max(axis=-1) > 1.0
    vb = b.max(axis=-1) > 1.0
    either = va | vb
    diff = float(np.abs(a - b)[either].mean()) if either.any() else 0.0
    return float(va.mean()), float(vb.mean()), diff


def coverage(png):
    np, a = read_rgb(png)
    return float((a.max(axis=-1) > 1.0).mean())


def derive_edges(ch2_raw, work):
    """The second channel of the two-channel rows: the MRI's gradient
    magnitude (central differences), scaled so its 99.5th percentile is
    255, as an 8-bit raw file on the same grid; returns its path."""
    import numpy as np

    dims = (181, 217, 181)
    a = np.fromfile(ch2_raw, dtype=np.uint8).reshape(dims[::-1]).astype(np.float32)
    g = np.sqrt(sum(d * d for d in np.gradient(a)))
    edges = np.clip(g / np.percentile(g, 99.5) * 255.0, 0, 255).astype(np.uint8)
    path = os.path.join(work, "ch2-edges_181x217x181_uint8.raw")
    edges.tofile(path)
    return path


def main(argv):
    args = parse_args(argv)
    try:
        import numpy  # noqa: F401
        import vtkmodules.vtkIOImage  # noqa: F401
    except ImportError as e:
        print(f"error: {e.name.split('.')[0]} is missing; install with: pip install vtk numpy; "
              "apt install libosmesa6", file=sys.stderr)
        return 2
    if not os.access(args.lacuna, os.X_OK):
        print(f"error: {args.lacuna} is not an executable lacuna; run cargo build --release", file=sys.stderr)
        return 2
    if not os.path.exists(CH2):
        print(f"error: {CH2} is missing; apt install mricron-data", file=sys.stderr)
        return 2
    images = os.path.join(os.path.dirname(args.out), "gallery")
    os.makedirs(images, exist_ok=True)
    os.makedirs(args.work, exist_ok=True)
    vtk_version = None
    results = {}
    try:
        raws = {}
        for key, _, spec in VOLUMES:
            if spec is None:
                continue
            lines = run([args.lacuna, "export", spec, os.path.join(args.work, key)]).strip().splitlines()
            if not lines or not os.path.exists(lines[-1]):
                raise Failure(f"lacuna export {spec} did not say what it wrote")
            raws[key] = lines[-1]
        raws[TWO] = raws["ch2"] + "+" + derive_edges(raws["ch2"], args.work)
        for vol, row, _, tf, look, mapper in ROWS:
            raw = raws[vol]
            tfs = [a for t in (tf if isinstance(tf, list) else [tf]) for a in ("--tf", t)]
            lpng = os.path.join(images, f"{vol}-{row}-lacuna.png")
            run([args.lacuna, "render", raw, *tfs, "--size", args.size,
                 "--camera", f"{CAMERA[0]:g},{CAMERA[1]:g}", "--background", "000000", "--out", lpng] + look)
            lcov = coverage(lpng)
            if lcov < 0.001:
                raise Failure(f"lacuna's {vol} {row} frame is empty")
            if mapper not in (CPU, GPU):
                results[(vol, row)] = {"lacuna": lpng, "lacuna_coverage": lcov}
                continue
            vpng = os.path.join(images, f"{vol}-{row}-vtk-{mapper}.png")
            out = run([sys.executable, os.path.join(HERE, "vtk.py"), raw, *tfs, "--size", args.size,
                       "--azimuth", f"{CAMERA[0]:g}", "--elevation", f"{CAMERA[1]:g}", "--frames", "1",
                       "--warmup", "0", "--mapper", mapper, "--ert", "on", "--png", vpng, "--srgb",
                       "--expect-coverage", f"{lcov:.6f}"] + look)
            vtk_version = json.loads(out)["vtk_version"]
            lc, vc, diff = compare(lpng, vpng)
            results[(vol, row)] = {"lacuna": lpng, "vtk": vpng, "lacuna_coverage": lc,
                                   "vtk_coverage": vc, "diff": diff}
    except Failure as e:
        print(f"error: {e}", file=sys.stderr)
        return 1

    w, h = args.size.split("x")
    md = [
        "# Gallery: lacuna's looks beside VTK's",
        "",
        "Made by `python3 bench/peers/gallery.py` (after `cargo build --release`; VTK from",
        "`pip install vtk numpy`, `apt install libosmesa6`). Do not edit by hand.",
        "",
        f"Each look renders the same raw file (`lacuna export`) with `lacuna render` and with VTK {vtk_version}",
        "through bench/peers/vtk.py, which sets VTK up the way lacuna frames and shades (its docstring says",
        f"how, and where VTK cannot follow): {w}x{h} pixels, orthographic, camera azimuth {CAMERA[0]:g},",
        f"elevation {CAMERA[1]:g}, sample distance 0.5 voxel, the same ramp transfer function over the",
        "volume's own value range, Phong weights 0.1, 0.7, 0.2, 10 under a headlight. VTK's image comes",
        "from its fixed-point CPU mapper where that has the mode, else from its GPU mapper (through",
        "OSMesa, llvmpipe); the column says which. Both over black, sRGB-encoded as lacuna's PNGs are",
        "(VTK's linear frame encoded the same way). Under each pair: visible pixels on each side and the",
        "mean difference of the 8-bit sRGB channels over the pixels either side shows, then what differs",
        "to the eye. The two-channel row gives each channel its own ParaView JSON transfer function",
        "(bench/peers/tf/) and VTK the two as independent components.",
        "",
        "Where VTK's shading departs from lacuna's: the CPU mapper lights quantised per-voxel normals and",
        "interpolates the lit colours; the GPU mapper's highlight is Phong's (R.V)^n, narrower than",
        "lacuna's Blinn (N.H)^n; both light a zero gradient with the ambient term only (lacuna: ambient +",
        "diffuse). VTK's iso surfaces are not refined between samples (lacuna bisects the crossing).",
        "",
    ]
    for key, title, _ in VOLUMES:
        rows = [r for r in ROWS if r[0] == key]
        md += [f"## {title}", "", "| look | lacuna | VTK |", "|---|---|---|"]
        for vol, row, rtitle, tf, look, mapper in rows:
            r = results[(vol, row)]
            rel = lambda p: os.path.relpath(p, os.path.dirname(args.out))  # noqa: E731
            shown = " ".join(look) if look else "(default)"
            tf_args = " ".join(f"--tf {t}" for t in (tf if isinstance(tf, list) else [tf]))
            head = f"**{rtitle}**<br>`{tf_args}`<br>`{shown}`"
            if "vtk" in r:
                vtk_cell = f"![VTK]({rel(r['vtk'])})<br>{MAPPER_LABEL[mapper]}"
            else:
                vtk_cell = mapper
            md.append(f"| {head} | ![lacuna]({rel(r['lacuna'])}) | {vtk_cell} |")
        md.append("")
        for vol, row, rtitle, tf, look, mapper in rows:
            r = results[(vol, row)]
            note = NOTES.get((vol, row), "")
            if "vtk" in r:
                nums = (f"visible lacuna {100 * r['lacuna_coverage']:.1f} %, VTK {100 * r['vtk_coverage']:.1f} %; "
                        f"mean |difference| {r['diff']:.1f}/255")
            else:
                nums = f"visible lacuna {100 * r['lacuna_coverage']:.1f} %; no VTK image"
            md.append(f"- **{rtitle}**: {nums}." + (f" {note}" if note else ""))
        md.append("")
    with open(args.out + ".tmp", "w") as f:
        f.write("\n".join(md))
    os.replace(args.out + ".tmp", args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
