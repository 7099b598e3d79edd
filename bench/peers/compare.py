#!/usr/bin/env python3
"""lacuna beside the renderers a user without a GPU would pick instead.

Writes docs/results/peers.md: on the same raw files, the same ramp transfer
function, sample distance, frame size and orthographic orbit, the frame
times of lacuna's structures (`lacuna bench`, GPU timestamps of the march
pass, interleaved rounds) and of VTK's two volume mappers (bench/peers/vtk.py,
wall time of Render + glFinish), with early ray termination off and on, and
one PNG of view 0 from each side per data set, so a reader sees that the
framing and the image match. A peer whose frame covers much less of the image
than lacuna's is not timed (vtk.py exits 1).

Usage (from the repository root, after `cargo build --release`):
    python3 bench/peers/compare.py [--lacuna target/release/lacuna]
        [--out docs/results/peers.md] [--work bench/out/peers]
        [--size 512x512] [--frames 6] [--rounds 3] [--step 0.5] [--quick]

`--quick` runs small volumes at 128x128 to check the script end to end
(a minute); its figures are not the ones to publish.

Requirements: a release build of lacuna, and for VTK `pip install vtk numpy`
and `apt install libosmesa6` (vtk.py checks both and says how to install
them). The ch2 brain MRI comes from Debian's mricron-data.
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

# (name, volume spec, transfer function, quick spec). Generators use their
# own default ramp (src/volume/procedural/mod.rs); ch2 the ramp of issue 11.
DATASETS = [
    ("nbody", "nbody:256", "ramp:0.35:1", "nbody:64"),
    ("vessels", "vessels:192", "ramp:0.3:1", "vessels:64"),
    ("menger", "menger:243", "ramp:0.3:1:0.2", "menger:81"),
    ("ch2", CH2, "ramp:0.3:0.6", CH2),
]
STRUCTURES = [("naive", "naive"), ("auto", "auto"), ("kd-cpu", "kd-cpu"), ("LBVH", "lbvh"), ("grid", "grid")]
ERT_ON = 0.99  # lacuna's threshold for "on"; VTK's are printed beside it


class Failure(Exception):
    pass


def run(cmd, capture=True):
    """Runs a command; a failure ends the script with its last stderr line."""
    shown = " ".join(shlex.quote(c) for c in cmd)
    print(f"$ {shown}", file=sys.stderr)
    p = subprocess.run(cmd, cwd=ROOT, capture_output=capture, text=True)
    if p.returncode != 0:
        last = (p.stderr or "").strip().splitlines()[-1:] or ["(no message)"]
        raise Failure(f"{cmd[0]} {cmd[1] if len(cmd) > 1 else ''} failed: {last[0]}")
    return p.stdout


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--lacuna", default=os.path.join(ROOT, "target", "release", "lacuna"))
    p.add_argument("--out", default=os.path.join(ROOT, "docs", "results", "peers.md"))
    p.add_argument("--work", default=os.path.join(ROOT, "bench", "out", "peers"))
    p.add_argument("--size", default="512x512")
    p.add_argument("--frames", type=int, default=6)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--step", type=float, default=0.5)
    p.add_argument("--quick", action="store_true")
    args = p.parse_args(argv)
    if args.quick:
        args.size = "128x128"
        args.frames = 2
        args.rounds = 2
    return args


def export(args, name, spec):
    stem = os.path.join(args.work, name)
    lines = run([args.lacuna, "export", spec, stem]).strip().splitlines()
    if not lines or not os.path.exists(lines[-1]):
        raise Failure(f"lacuna export {spec} did not say what it wrote")
    return lines[-1]


def lacuna_bench(args, name, raw, tf, ert):
    """Every structure, interleaved; returns results.json's records."""
    tag = f"{name}-ert-{'on' if ert else 'off'}"
    w, h = args.size.split("x")
    lines = [
        f'name = "peers-{tag}"',
        f"size = [{w}, {h}]",
        f"frames = {args.frames}",
        "warmup = 2",
        "builds = 1",
        f"rounds = {args.rounds}",
        f"step = {args.step}",
        "elevation = 20.0",
    ]
    if ert:
        lines.append(f"ert = {ERT_ON}")
    lines += ["", "[[dataset]]", f'volume = "{raw}"', f'tf = "{tf}"']
    for label, accel in STRUCTURES:
        lines += ["", "[[structure]]", f'label = "{label}"', f'accel = "{accel}"']
    config = os.path.join(args.work, f"{tag}.toml")
    with open(config, "w") as f:
        f.write("\n".join(lines) + "\n")
    out_dir = os.path.join(args.work, tag)
    run([args.lacuna, "bench", config, "--out", out_dir, "--quiet"])
    with open(os.path.join(out_dir, "results.json")) as f:
        return json.load(f)


def flatten_png(path):
    """lacuna's PNG has straight alpha; VTK's is RGB over black. Rewrites
    lacuna's over black, as VTK's, and returns its coverage: the fraction of
    pixels with alpha above 1/255 (vtk.py's test on the same view)."""
    # vtkmodules, not `vtk`: this folder's vtk.py would shadow it.
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOImage import vtkPNGReader, vtkPNGWriter
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy

    r = vtkPNGReader()
    r.SetFileName(path)
    r.Update()
    img = r.GetOutput()
    n = img.GetNumberOfScalarComponents()
    if n != 4:
        raise Failure(f"{path}: expected RGBA from lacuna render, got {n} channels")
    a = vtk_to_numpy(img.GetPointData().GetScalars()).reshape(-1, 4).astype("float64")
    rgb = (a[:, :3] * a[:, 3:4] / 255.0 + 0.5).clip(0, 255).astype("uint8")
    out = vtkImageData()
    out.SetDimensions(img.GetDimensions())
    out.GetPointData().SetScalars(numpy_to_vtk(rgb, deep=True))
    w = vtkPNGWriter()
    w.SetFileName(path)
    w.SetInputData(out)
    w.Write()
    return float((a[:, 3] > 1).mean())


def lacuna_png(args, raw, tf, ert, path):
    cmd = [args.lacuna, "render", raw, "--tf", tf, "--size", args.size, "--camera", "0,20",
           "--step", str(args.step), "--accel", "naive", "--out", path]
    if ert:
        cmd += ["--ert", str(ERT_ON)]
    run(cmd)


def vtk_peer(args, raw, tf, ert, png, expect):
    out = run([sys.executable, os.path.join(HERE, "vtk.py"), raw, "--tf", tf, "--size", args.size,
               "--step", str(args.step), "--frames", str(args.frames), "--mapper", "both",
               "--ert", "on" if ert else "off", "--png", png, "--expect-coverage", f"{expect:.6f}"])
    return json.loads(out)


def fmt(ms, lo, hi):
    return f"{ms:.1f} [{lo:.1f}, {hi:.1f}]"


def main(argv):
    args = parse_args(argv)
    try:
        import numpy  # noqa: F401
        import vtkmodules.vtkIOImage  # noqa: F401
    except ImportError as e:
        print(f"error: {e.name.split('.')[0]} is missing; install with: pip install vtk numpy; apt install libosmesa6",
              file=sys.stderr)
        return 2
    if not os.access(args.lacuna, os.X_OK):
        print(f"error: {args.lacuna} is not an executable lacuna; run cargo build --release", file=sys.stderr)
        return 2
    os.makedirs(args.work, exist_ok=True)
    images = os.path.join(os.path.dirname(args.out), "peers")
    os.makedirs(images, exist_ok=True)
    sections = []
    setup = None
    try:
        for name, spec, tf, quick_spec in DATASETS:
            spec = quick_spec if args.quick else spec
            if spec == CH2 and not os.path.exists(CH2):
                raise Failure(f"{CH2} is missing; apt install mricron-data")
            raw = export(args, name, spec)
            rows = {}
            pngs = {}
            for ert in (False, True):
                records = lacuna_bench(args, name, raw, tf, ert)
                setup = setup or records[0]
                for r in records:
                    f = r["frame"]
                    rows.setdefault(r["structure"], {})[ert] = (
                        fmt(f["median_ms"], f["min_ms"], f["max_ms"]) + (" †" if r["unstable"] else ""),
                        f["median_ms"], r["speedup"])
                png = os.path.join(images, f"{name}-lacuna{'-ert' if ert else ''}.png")
                lacuna_png(args, raw, tf, ert, png)
                cov = flatten_png(png)
                vpng = os.path.join(images, f"{name}-vtk{'-ert' if ert else ''}.png")
                peer = vtk_peer(args, raw, tf, ert, vpng, cov)
                for kind, label in (("cpu", "VTK CPU (fixed point)"), ("gpu", "VTK GPU (llvmpipe)")):
                    m = peer["mappers"][kind]
                    rows.setdefault(label, {})[ert] = (fmt(m["median_ms"], m["min_ms"], m["max_ms"]),
                                                       m["median_ms"], None)
                    rows[label].setdefault("coverage", {})[ert] = m["coverage"]
                    rows[label].setdefault("ert_info", {})[ert] = m["ert"]
                rows.setdefault("lacuna coverage", {})[ert] = cov
                if not ert:
                    pngs = {"lacuna": png, "cpu": vpng.replace(".png", "-cpu.png"),
                            "gpu": vpng.replace(".png", "-gpu.png")}
                    vtk_version = peer["vtk_version"]
                    dims, vtype = peer["dims"], peer["type"]
            sections.append((name, spec, tf, raw, dims, vtype, rows, pngs))
    except Failure as e:
        print(f"error: {e}", file=sys.stderr)
        return 1

    cmd = "python3 bench/peers/compare.py" + (" --quick" if args.quick else "")
    md = [
        "# lacuna beside VTK's ray casters",
        "",
        f"Made by `{cmd}` (after `cargo build --release`; VTK from `pip install vtk numpy`,",
        "`apt install libosmesa6`). Do not edit by hand.",
        "",
        f"Machine: {setup['device']} ({setup['driver']}), {os.cpu_count()} CPU threads; VTK {vtk_version}",
        "through OSMesa (llvmpipe). Every side renders the same raw file (written by `lacuna export`), the",
        f"same ramp over the volume's own value range, {args.size} pixels, sample distance {args.step} voxel,",
        f"orthographic orbit at elevation 20 zoomed so the box fills the frame, {args.frames} views.",
        "",
        "Frame ms: median [min, max]. lacuna: GPU timestamps of the march pass, every view timed in",
        f"{args.rounds} rounds interleaved with the other structures after a warm-up until stable (`lacuna",
        "bench`); x: speed-up over naive in the same rounds; † unstable (a view's times spread more than",
        "1.5x). VTK: wall time of Render + glFinish per view after one untimed view; the CPU mapper",
        "always terminates rays early (alpha > 0.992, compiled in) and skips empty 4^3 cells; the GPU",
        "mapper skips nothing and terminates at alpha > 0.996 when on. lacuna's ERT on is",
        f"`--ert {ERT_ON}`. The machine is shared: compare within a table, not across runs.",
        "",
    ]
    for name, spec, tf, raw, dims, vtype, rows, pngs in sections:
        md += [f"## {name}: `{spec}`, {dims[0]}x{dims[1]}x{dims[2]} {vtype}, `{tf}`", ""]
        md += ["| renderer | ERT off | ERT on | ERT on vs VTK CPU |", "|---|---|---|---|"]
        vtk_cpu_on = rows["VTK CPU (fixed point)"][True][1]
        for label, r in rows.items():
            if label == "lacuna coverage":
                continue
            cells = []
            for ert in (False, True):
                text, _, speedup = r[ert]
                cells.append(text + (f" ({speedup:.2f}x)" if speedup is not None else ""))
            if label == "VTK CPU (fixed point)":
                cells[0] += " (terminates early anyway)"
            ratio = r[True][1] / vtk_cpu_on
            shown = label if label.startswith("VTK") else f"lacuna {label}"
            md.append(f"| {shown} | {cells[0]} | {cells[1]} | {ratio:.2f}x the time |")
        cov = rows["lacuna coverage"][False]
        vcov = rows["VTK CPU (fixed point)"]["coverage"][False]
        gcov = rows["VTK GPU (llvmpipe)"]["coverage"][False]
        md += ["", f"Visible pixels in view 0 (ERT off): lacuna {100 * cov:.1f} %, VTK CPU {100 * vcov:.1f} %,"
               f" VTK GPU {100 * gcov:.1f} %.", ""]
        rel = {k: os.path.relpath(v, os.path.dirname(args.out)) for k, v in pngs.items()}
        md += ["| lacuna | VTK CPU | VTK GPU |", "|---|---|---|",
               f"| ![lacuna]({rel['lacuna']}) | ![VTK CPU]({rel['cpu']}) | ![VTK GPU]({rel['gpu']}) |", ""]
    with open(args.out + ".tmp", "w") as f:
        f.write("\n".join(md))
    os.replace(args.out + ".tmp", args.out)
    # ERT-on PNGs only served the coverage check.
    for name, *_ in sections:
        for p in (f"{name}-lacuna-ert.png", f"{name}-vtk-ert-cpu.png", f"{name}-vtk-ert-gpu.png"):
            path = os.path.join(images, p)
            if os.path.exists(path):
                os.remove(path)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
