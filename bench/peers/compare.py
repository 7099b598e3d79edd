#!/usr/bin/env python3
"""lacuna beside the renderers a user without a GPU would pick instead.

Writes docs/results/peers.md: on the same raw files, the same ramp transfer
function, sample distance, frame size and orthographic orbit, the frame
times of lacuna's structures (`lacuna bench`, GPU timestamps of the march
pass, interleaved rounds) and of VTK's two volume mappers (bench/peers/vtk.py,
wall time of Render + glFinish), in three looks per data set:

- composite: emission-absorption, unshaded, early ray termination off and on
  (every structure of STRUCTURES);
- shaded: composite with Blinn-Phong shading under a headlight (0.1, 0.7,
  0.2, 10 on both sides), early ray termination on (VTK's CPU mapper always
  terminates early), naive, auto and the fastest other structures
  (LOOK_STRUCTURES);
- mip: maximum intensity projection (no early ray termination: nothing
  accumulates), the same structures.

Each look gets one PNG of view 0 from each side per data set, so a reader
sees that the framing and the image match. A peer whose frame covers much
less of the image than lacuna's is not timed (vtk.py exits 1). A summary at
the top says, per data set, whether lacuna's shaded and MIP frames beat VTK's
CPU caster (the fastest structure and auto, against VTK CPU's median).

Usage (from the repository root, after `cargo build --release`):
    python3 bench/peers/compare.py [--lacuna target/release/lacuna]
        [--out docs/results/peers.md] [--work bench/out/peers]
        [--size 512x512] [--frames 6] [--rounds 3] [--step 0.5]
        [--looks composite,shaded,mip] [--quick]

`--quick` runs small volumes at 128x128 to check the script end to end
(a few minutes); its figures are not the ones to publish. `--looks` picks
the looks to run (default all three); the page then holds only those.

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
import time

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
# The shaded and MIP looks: naive, auto and the structures that came next in
# the composite tables (LBVH trails them everywhere), to keep the run short.
LOOK_STRUCTURES = [("naive", "naive"), ("auto", "auto"), ("kd-cpu", "kd-cpu"), ("grid", "grid")]
ERT_ON = 0.99  # lacuna's threshold for "on"; VTK's are printed beside it
# look -> (title, lacuna bench `look` table, `lacuna render` and vtk.py
# options, ERT on?). ERT: shaded frames are timed with it on (VTK's CPU
# mapper cannot turn it off); MIP has none (lacuna refuses it, VTK ignores it).
LOOKS = {
    "composite": ("composite", None, [], None),
    "shaded": ("shaded composite", "{ shade = true }", ["--shade", "on"], True),
    "mip": ("MIP", '{ mode = "mip" }', ["--mode", "mip"], False),
}
CPU_LABEL = "VTK CPU (fixed point)"
GPU_LABEL = "VTK GPU (llvmpipe)"


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


def parse_looks(text):
    looks = [w.strip() for w in text.split(",") if w.strip()]
    bad = [w for w in looks if w not in LOOKS]
    if bad or not looks:
        raise argparse.ArgumentTypeError(f"'{text}': expected a comma-separated subset of {','.join(LOOKS)}")
    return [w for w in LOOKS if w in looks]  # page order


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--lacuna", default=os.path.join(ROOT, "target", "release", "lacuna"))
    p.add_argument("--out", default=os.path.join(ROOT, "docs", "results", "peers.md"))
    p.add_argument("--work", default=os.path.join(ROOT, "bench", "out", "peers"))
    p.add_argument("--size", default="512x512")
    p.add_argument("--frames", type=int, default=6)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--step", type=float, default=0.5)
    p.add_argument("--looks", type=parse_looks, default=list(LOOKS),
                   help="comma-separated looks to run: composite,shaded,mip (default all)")
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


def lacuna_bench(args, name, raw, tf, ert, look, structures):
    """The structures, interleaved, in one look; returns results.json's records."""
    tag = f"{name}-{look}-ert-{'on' if ert else 'off'}"
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
    if LOOKS[look][1]:
        lines.append(f"look = {LOOKS[look][1]}")
    for label, accel in structures:
        lines += ["", "[[structure]]", f'label = "{label}"', f'accel = "{accel}"']
    config = os.path.join(args.work, f"{tag}.toml")
    with open(config, "w") as f:
        f.write("\n".join(lines) + "\n")
    out_dir = os.path.join(args.work, tag)
    run([args.lacuna, "bench", config, "--out", out_dir, "--quiet"])
    with open(os.path.join(out_dir, "results.json")) as f:
        return json.load(f)


# ------------------------------------------------------------------ images
# lacuna's PNGs are 8-bit sRGB with straight alpha; vtk.py --srgb writes
# VTK's (linear, premultiplied) frame sRGB-encoded over black. The page shows
# both over black, sRGB-encoded, at half size (2x2 means in linear light).


def srgb_decode(np, encoded):
    return np.where(encoded <= 0.04045, encoded / 12.92, ((encoded + 0.055) / 1.055) ** 2.4)


def srgb_encode(np, linear):
    linear = np.clip(linear, 0.0, 1.0)
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1.0 / 2.4) - 0.055)


def read_png(path):
    """(numpy, float array height x width x channels in [0, 1], row 0 at the bottom)."""
    # vtkmodules, not `vtk`: this folder's vtk.py would shadow it.
    import numpy as np
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOImage import vtkPNGReader

    r = vtkPNGReader()
    r.SetFileName(path)
    r.Update()
    img = r.GetOutput()
    w, h, _ = img.GetDimensions()
    n = img.GetNumberOfScalarComponents()
    return np, vtk_to_numpy(img.GetPointData().GetScalars()).reshape(h, w, n).astype("float64") / 255.0


def write_png(np, path, linear_rgb, half):
    """Linear RGB (row 0 at the bottom) as an sRGB PNG, 2x2-averaged when `half`."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOImage import vtkPNGWriter

    if half and linear_rgb.shape[0] % 2 == 0 and linear_rgb.shape[1] % 2 == 0:
        h, w, c = linear_rgb.shape
        linear_rgb = linear_rgb.reshape(h // 2, 2, w // 2, 2, c).mean(axis=(1, 3))
    h, w, _ = linear_rgb.shape
    rgb = (srgb_encode(np, linear_rgb) * 255.0 + 0.5).astype("uint8")
    out = vtkImageData()
    out.SetDimensions(w, h, 1)
    out.GetPointData().SetScalars(numpy_to_vtk(np.ascontiguousarray(rgb).reshape(-1, 3), deep=True))
    wr = vtkPNGWriter()
    wr.SetFileName(path)
    wr.SetInputData(out)
    wr.Write()


def flatten_lacuna_png(path, half=True):
    """Rewrites lacuna's straight-alpha PNG over black (as VTK's) and returns
    its coverage: the fraction of pixels with alpha above 1/255 (vtk.py's
    test on the same view)."""
    np, a = read_png(path)
    if a.shape[2] != 4:
        raise Failure(f"{path}: expected RGBA from lacuna render, got {a.shape[2]} channels")
    write_png(np, path, srgb_decode(np, a[..., :3]) * a[..., 3:4], half)
    return float((a[..., 3] > 1.5 / 255.0).mean())


def shrink_vtk_png(path, half=True):
    """VTK's sRGB PNG at half size."""
    if half:
        np, a = read_png(path)
        write_png(np, path, srgb_decode(np, a[..., :3]), half)


def lacuna_png(args, raw, tf, ert, look, path):
    cmd = [args.lacuna, "render", raw, "--tf", tf, "--size", args.size, "--camera", "0,20",
           "--step", str(args.step), "--accel", "naive", "--out", path] + LOOKS[look][2]
    if ert:
        cmd += ["--ert", str(ERT_ON)]
    run(cmd)


def vtk_peer(args, raw, tf, ert, look, png, expect, mapper="both"):
    out = run([sys.executable, os.path.join(HERE, "vtk.py"), raw, "--tf", tf, "--size", args.size,
               "--step", str(args.step), "--frames", str(args.frames), "--mapper", mapper,
               "--ert", "on" if ert else "off", "--png", png, "--srgb",
               "--expect-coverage", f"{expect:.6f}"] + LOOKS[look][2])
    return json.loads(out)


def fmt(ms, lo, hi):
    return f"{ms:.1f} [{lo:.1f}, {hi:.1f}]"


def versus(ms, cpu_ms):
    """This renderer's time against VTK CPU's, plainly."""
    r = cpu_ms / ms
    if r >= 1.0:
        return f"{r:.2f}x faster"
    return f"{1.0 / r:.2f}x slower"


# ------------------------------------------------------------------ runs


def run_composite(args, name, raw, tf, images):
    """Today's table: every structure, ERT off and on. Returns the section data."""
    rows, pngs, peer0, setup = {}, {}, None, None
    for ert in (False, True):
        records = lacuna_bench(args, name, raw, tf, ert, "composite", STRUCTURES)
        for r in records:
            f = r["frame"]
            rows.setdefault(r["structure"], {})[ert] = (
                fmt(f["median_ms"], f["min_ms"], f["max_ms"]) + (" †" if r["unstable"] else ""),
                f["median_ms"], r["speedup"])
        png = os.path.join(images, f"{name}-lacuna{'-ert' if ert else ''}.png")
        lacuna_png(args, raw, tf, ert, "composite", png)
        cov = flatten_lacuna_png(png)
        vpng = os.path.join(images, f"{name}-vtk{'-ert' if ert else ''}.png")
        peer = vtk_peer(args, raw, tf, ert, "composite", vpng, cov)
        for kind, label in (("cpu", CPU_LABEL), ("gpu", GPU_LABEL)):
            m = peer["mappers"][kind]
            rows.setdefault(label, {})[ert] = (fmt(m["median_ms"], m["min_ms"], m["max_ms"]),
                                               m["median_ms"], None)
            rows[label].setdefault("coverage", {})[ert] = m["coverage"]
        rows.setdefault("lacuna coverage", {})[ert] = cov
        if not ert:
            pngs = {"lacuna": png, "cpu": vpng.replace(".png", "-cpu.png"),
                    "gpu": vpng.replace(".png", "-gpu.png")}
            for k in ("cpu", "gpu"):
                shrink_vtk_png(pngs[k])
            peer0 = peer
        else:
            # ERT-on PNGs only served the coverage check.
            for p in (png, vpng.replace(".png", "-cpu.png"), vpng.replace(".png", "-gpu.png")):
                if os.path.exists(p):
                    os.remove(p)
        setup = setup or records[0]
    return {"rows": rows, "pngs": pngs, "peer": peer0, "setup": setup}


def run_look(args, name, raw, tf, look, images):
    """A shaded or MIP table: LOOK_STRUCTURES and both VTK mappers in one look."""
    ert = LOOKS[look][3]
    records = lacuna_bench(args, name, raw, tf, ert, look, LOOK_STRUCTURES)
    rows = {}
    for r in records:
        f = r["frame"]
        rows[r["structure"]] = {
            "text": fmt(f["median_ms"], f["min_ms"], f["max_ms"]) + (" †" if r["unstable"] else ""),
            "ms": f["median_ms"], "speedup": r["speedup"], "chosen": r.get("chosen")}
    png = os.path.join(images, f"{name}-{look}-lacuna.png")
    lacuna_png(args, raw, tf, ert, look, png)
    cov = flatten_lacuna_png(png)
    vpng = os.path.join(images, f"{name}-{look}-vtk.png")
    peer = vtk_peer(args, raw, tf, ert, look, vpng, cov)
    for kind, label in (("cpu", CPU_LABEL), ("gpu", GPU_LABEL)):
        m = peer["mappers"][kind]
        rows[label] = {"text": fmt(m["median_ms"], m["min_ms"], m["max_ms"]), "ms": m["median_ms"],
                       "speedup": None, "coverage": m["coverage"], "ert": m["ert"]}
    pngs = {"lacuna": png, "cpu": vpng.replace(".png", "-cpu.png"), "gpu": vpng.replace(".png", "-gpu.png")}
    for k in ("cpu", "gpu"):
        shrink_vtk_png(pngs[k])
    return {"rows": rows, "pngs": pngs, "coverage": cov, "peer": peer, "setup": records[0]}


# ------------------------------------------------------------------ page


def image_table(md, out, pngs):
    rel = {k: os.path.relpath(v, os.path.dirname(out)) for k, v in pngs.items()}
    md += ["| lacuna | VTK CPU | VTK GPU |", "|---|---|---|",
           f"| ![lacuna]({rel['lacuna']}) | ![VTK CPU]({rel['cpu']}) | ![VTK GPU]({rel['gpu']}) |", ""]


def composite_section(md, args, sec):
    rows = sec["rows"]
    md += ["### composite (unshaded), ERT off and on", ""]
    md += ["| renderer | ERT off | ERT on | ERT on vs VTK CPU |", "|---|---|---|---|"]
    vtk_cpu_on = rows[CPU_LABEL][True][1]
    for label, r in rows.items():
        if label == "lacuna coverage":
            continue
        cells = []
        for ert in (False, True):
            text, _, speedup = r[ert]
            cells.append(text + (f" ({speedup:.2f}x)" if speedup is not None else ""))
        if label == CPU_LABEL:
            cells[0] += " (terminates early anyway)"
        ratio = r[True][1] / vtk_cpu_on
        shown = label if label.startswith("VTK") else f"lacuna {label}"
        md.append(f"| {shown} | {cells[0]} | {cells[1]} | {ratio:.2f}x the time |")
    cov = rows["lacuna coverage"][False]
    vcov = rows[CPU_LABEL]["coverage"][False]
    gcov = rows[GPU_LABEL]["coverage"][False]
    md += ["", f"Visible pixels in view 0 (ERT off): lacuna {100 * cov:.1f} %, VTK CPU {100 * vcov:.1f} %,"
           f" VTK GPU {100 * gcov:.1f} %.", ""]
    image_table(md, args.out, sec["pngs"])


def fastest_lacuna(rows):
    lac = {k: v for k, v in rows.items() if not k.startswith("VTK")}
    best = min(lac, key=lambda k: lac[k]["ms"])
    return best, lac[best]


def look_section(md, args, look, sec):
    title = LOOKS[look][0]
    ert = LOOKS[look][3]
    rows = sec["rows"]
    cpu_ms = rows[CPU_LABEL]["ms"]
    when = "ERT on (lacuna `--ert 0.99`)" if ert else "no ERT (nothing accumulates)"
    md += [f"### {title}, {when}", ""]
    md += ["| renderer | frame ms | x naive | vs VTK CPU |", "|---|---|---|---|"]
    for label, r in rows.items():
        shown = label if label.startswith("VTK") else f"lacuna {label}"
        if label == "auto" and r.get("chosen"):
            shown += f" (chose {r['chosen']})"
        sp = f"{r['speedup']:.2f}x" if r["speedup"] is not None else ""
        vs = "1.00x (reference)" if label == CPU_LABEL else versus(r["ms"], cpu_ms)
        md.append(f"| {shown} | {r['text']} | {sp} | {vs} |")
    md += ["", f"Visible pixels in view 0: lacuna {100 * sec['coverage']:.1f} %, VTK CPU "
           f"{100 * rows[CPU_LABEL]['coverage']:.1f} %, VTK GPU {100 * rows[GPU_LABEL]['coverage']:.1f} %.", ""]
    image_table(md, args.out, sec["pngs"])


def summary(md, sections, looks):
    """Per data set and look: lacuna's fastest structure and auto against VTK CPU."""
    lit = [lk for lk in looks if lk != "composite"]
    if not lit:
        return
    md += ["## Shaded composite and MIP against VTK's CPU caster", "",
           "Median frame ms as in the tables below; \"beats\": lacuna's median is below VTK CPU's.", "",
           "| data set | look | lacuna fastest | lacuna auto | VTK CPU | fastest vs VTK CPU | beats VTK CPU |",
           "|---|---|---|---|---|---|---|"]
    verdicts = []
    for sec in sections:
        for look in lit:
            s = sec["looks"][look]
            rows = s["rows"]
            cpu = rows[CPU_LABEL]["ms"]
            best, b = fastest_lacuna(rows)
            auto = rows.get("auto")
            beats = b["ms"] < cpu
            verdicts.append(beats)
            auto_cell = f"{auto['ms']:.1f} ({versus(auto['ms'], cpu)})" if auto else "-"
            md.append(f"| {sec['name']} | {LOOKS[look][0]} | {best}: {b['ms']:.1f} | {auto_cell} | {cpu:.1f} | "
                      f"{versus(b['ms'], cpu)} | {'yes' if beats else '**no**'} |")
    n = len(verdicts)
    md += ["", (f"lacuna's fastest structure beats VTK CPU in all {n} cases." if all(verdicts) else
                f"lacuna's fastest structure beats VTK CPU in {sum(verdicts)} of {n} cases; "
                "the rows marked **no** are where it loses."), ""]


def prerequisites(lacuna):
    """Whether VTK, numpy and an executable lacuna are there; an error line
    naming what is missing otherwise."""
    try:
        import numpy  # noqa: F401
        import vtkmodules.vtkIOImage  # noqa: F401
    except ImportError as e:
        print(f"error: {e.name.split('.')[0]} is missing; install with: pip install vtk numpy; apt install libosmesa6",
              file=sys.stderr)
        return False
    if not os.access(lacuna, os.X_OK):
        print(f"error: {lacuna} is not an executable lacuna; run cargo build --release", file=sys.stderr)
        return False
    return True


def main(argv):
    args = parse_args(argv)
    if not prerequisites(args.lacuna):
        return 2
    os.makedirs(args.work, exist_ok=True)
    images = os.path.join(os.path.dirname(args.out), "peers")
    os.makedirs(images, exist_ok=True)
    sections = []
    setup = None
    vtk_version = None
    started = time.monotonic()
    try:
        for name, spec, tf, quick_spec in DATASETS:
            spec = quick_spec if args.quick else spec
            if spec == CH2 and not os.path.exists(CH2):
                raise Failure(f"{CH2} is missing; apt install mricron-data")
            raw = export(args, name, spec)
            sec = {"name": name, "spec": spec, "tf": tf, "looks": {}}
            for look in args.looks:
                if look == "composite":
                    s = run_composite(args, name, raw, tf, images)
                else:
                    s = run_look(args, name, raw, tf, look, images)
                sec["looks"][look] = s
                setup = setup or s["setup"]
                vtk_version = s["peer"]["vtk_version"]
                sec["dims"], sec["type"] = s["peer"]["dims"], s["peer"]["type"]
            sections.append(sec)
    except Failure as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    wall_min = (time.monotonic() - started) / 60.0

    cmd = "python3 bench/peers/compare.py" + (" --quick" if args.quick else "")
    if args.looks != list(LOOKS):
        cmd += f" --looks {','.join(args.looks)}"
    md = [
        "# lacuna beside VTK's ray casters",
        "",
        f"Made by `{cmd}` (after `cargo build --release`; VTK from `pip install vtk numpy`,",
        f"`apt install libosmesa6`), in one run of {wall_min:.0f} minutes. Do not edit by hand.",
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
        "Looks (per data set and look, lacuna's bench run is followed at once by VTK's on the same look):",
        "",
    ]
    if "composite" in args.looks:
        md += ["- **composite**: emission-absorption, unshaded, ERT off and on, lacuna's structures "
               f"{', '.join(label for label, _ in STRUCTURES)}."]
    if "shaded" in args.looks:
        md += ["- **shaded composite**: the same with Blinn-Phong shading under a headlight, ambient 0.1,",
               "  diffuse 0.7, specular 0.2, power 10 (VTK's defaults) on both sides, ERT on (VTK CPU cannot",
               f"  turn it off), lacuna's {', '.join(label for label, _ in LOOK_STRUCTURES)}. VTK's shading",
               "  departs from lacuna's in detail (bench/peers/vtk.py's docstring: per-voxel quantised normals",
               "  on the CPU mapper, a Phong rather than Blinn highlight on the GPU mapper; docs/gallery.md",
               "  shows the images side by side)."]
    if "mip" in args.looks:
        md += ["- **MIP**: maximum intensity projection through the TF, no ERT (nothing accumulates), lacuna's",
               f"  {', '.join(label for label, _ in LOOK_STRUCTURES)}."]
    md += ["",
           "The shaded and MIP tables give each renderer's time against VTK CPU's (\"x faster\" / \"x slower\"),",
           "and the summary below collects them. Images: view 0 of each side over black, sRGB-encoded as",
           "lacuna's PNGs are (VTK's linear frame encoded the same way), at half size.", ""]
    summary(md, sections, args.looks)
    for sec in sections:
        dims = sec["dims"]
        md += [f"## {sec['name']}: `{sec['spec']}`, {dims[0]}x{dims[1]}x{dims[2]} {sec['type']}, `{sec['tf']}`", ""]
        for look in args.looks:
            if look == "composite":
                composite_section(md, args, sec["looks"][look])
            else:
                look_section(md, args, look, sec["looks"][look])
    with open(args.out + ".tmp", "w") as f:
        f.write("\n".join(md))
    os.replace(args.out + ".tmp", args.out)
    print(f"wrote {args.out} ({wall_min:.1f} min)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
