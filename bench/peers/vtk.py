#!/usr/bin/env python3
"""Peer benchmark: render lacuna's benchmark work with VTK on the CPU.

Renders a raw volume the way `lacuna bench` and `lacuna render` do
(orthographic orbit camera zoomed so the projected volume box fills the
viewport, post-classification, lacuna's `ramp` transfer function, the same
sample distance, and lacuna's looks: emission-absorption with or without
Blinn-Phong shading, maximum and minimum intensity projection, iso surfaces)
with VTK's two volume mappers, offscreen through OSMesa, and prints per-frame
wall times as JSON. It is what a user without a GPU would reach for, so
lacuna's docs can say how they compare.

Usage:
    python3 bench/peers/vtk.py VOLUME.raw [--tf ramp:LO:HI[:ALPHA]]
        [--mode composite|mip|minip|iso] [--iso V[,V2..]] [--shade on|off]
        [--phong KA,KD,KS,N] [--crop X0:X1,Y0:Y1,Z0:Z1]
        [--size 512x512] [--step 0.5] [--frames 6] [--warmup 1]
        [--elevation 20] [--azimuth 0] [--mapper cpu|gpu|both] [--ert off|on]
        [--png frame0.png] [--srgb] [--expect-coverage X] [--min-coverage 0.001]

    python3 bench/peers/vtk.py /data/skull_256x256x256_uint8.raw \\
        --tf ramp:0.3:0.6 --mapper both --frames 6 --png /tmp/skull.png
    python3 bench/peers/vtk.py /data/skull_256x256x256_uint8.raw \\
        --tf ramp:0.3:0.6 --shade on --ert on --png /tmp/skull-shaded.png

Requirements: numpy and VTK 9.x from pip (`pip install vtk numpy`), and
Mesa's OSMesa (`apt install libosmesa6`). The script selects VTK's OSMesa
window itself (VTK_DEFAULT_OPENGL_WINDOW=vtkOSOpenGLRenderWindow, honoured by
the pip wheels since VTK 9.4); no display is needed. Missing either prints
one `error:` line and exits 2.

What it reproduces from lacuna (src/render/camera.rs, src/tf.rs,
src/volume/mod.rs, glsl/common/lattice.glsl, glsl/common/light.glsl):

- Input: an Open SciVis raw file `name_WxHxD_TYPE.raw`, little-endian, x
  fastest, spacing 1. TYPE: uint8, int8, uint16, int16, float32, float64.
  Voxel i sits at i + 0.5, so the volume box is [0, W] x [0, H] x [0, D] as in
  lacuna's voxel space (VTK's world coordinates here are lacuna's voxel
  coordinates).
- Normalisation: lacuna maps every voxel type linearly over the volume's own
  value range, v = (raw - min) / (max - min) (for uint8 that is not raw/255
  unless the data spans 0..255). The transfer function and the iso values
  are therefore placed over [min, max] in raw units: raw = min + v * (max - min).
- Transfer function `ramp:LO:HI[:ALPHA]`: lacuna's 1024-entry LUT over
  v in [0, 1]: colour = its violet-orange-yellow colormap at v, alpha =
  ALPHA * clamp((v - LO) / (HI - LO), 0, 1) per voxel of path length. Every
  LUT entry becomes a point of the vtkColorTransferFunction and the
  vtkPiecewiseFunction (linear interpolation between entries, as lacuna's
  lookup). The opacity unit distance is 1 voxel, and both mappers correct
  opacity for the sample distance as lacuna does (composite only).
- Camera: azimuth and elevation about the volume centre, y up; view i of N
  is at azimuth `--azimuth` + 360 * i / N (the bench orbit starts at 0) and
  `--elevation` (default 20, as bench/quick.toml and bench/paper.toml).
  Orthographic, with the parallel scale lacuna computes: the projected box
  corners fit the viewport. Row 0 of the PNG is the top, as in lacuna's EXR.
  Unlit looks put the eye 1 voxel outside the bounding sphere (lacuna's
  distance); lit looks put it 1000 bounding-sphere radii away, which changes
  nothing in an orthographic image but makes the GPU mapper's headlight (a
  light at the eye position, whose direction it takes per fragment from the
  eye to the box face) parallel to the view, as lacuna's is (off by at most
  1 mrad).
- `--step S`: sample distance S voxels along the ray (spacing 1, so world
  units), fixed: automatic sample-distance adjustment is off for both mappers
  and the CPU mapper casts one ray per pixel (image sample distance 1).
- `--crop X0:X1,Y0:Y1,Z0:Z1`: lacuna's crop box in voxel coordinates, as
  the mapper's cropping region planes (sub-volume flags).

Looks (`--mode`, `--shade`, `--phong`, `--iso`), each as the mappers have it:

- composite (default): emission-absorption front to back. `--shade on`
  lights every sample with Blinn-Phong: vtkVolumeProperty ShadeOn with
  SetAmbient/SetDiffuse/SetSpecular/SetSpecularPower from `--phong
  KA,KD,KS,N` (default 0.1,0.7,0.2,10, VTK's and lacuna's defaults), and one
  white headlight of intensity 1 added to the renderer (the light VTK's
  renderer would create by itself, with its ambient colour set to white: the
  CPU mapper multiplies KA by the light's ambient colour, black by default,
  where lacuna and the GPU mapper take KA as is). Both sides: colour = TF
  colour * (KA + KD |N.L|) + KS (N.H)^N, two-sided, normal from central
  differences of the scalar field, alpha unchanged. Where the mappers depart
  from lacuna's model (VTK does not let us change these):
  * CPU: normals are computed per voxel (central differences of the raw
    voxels, one-sided at the faces; float data retries 2 and 3 voxels apart
    where they vanish), quantised to one of ~10^4 directions, lit per voxel,
    and the lit colours of a cell's 8 corners interpolated (lacuna
    interpolates the gradient, then lights); the highlight is Blinn-Phong
    with H = L (headlight), as lacuna's. A voxel with a zero gradient gets
    the ambient term only (lacuna: KA + KD, no specular).
  * GPU: the gradient is taken at each sample (central differences one voxel
    apart on the interpolated field), and the highlight is Phong's
    (R.V)^N = (2 (N.L)^2 - 1)^N with a headlight, not Blinn's (N.H)^N, so it
    is narrower (as if N were about 4x larger). A zero gradient gets the
    ambient term only (lacuna: KA + KD).
- mip / minip: the largest / smallest scalar sample along the ray, then its
  colour and opacity from the TF (no sample-distance correction), as
  lacuna's. Unlit (`--shade on` is refused, as lacuna refuses it). GPU
  mapper with `--crop`: a ray that has no sample inside the crop box keeps
  the shader's starting extreme and shows the TF at 0 (mip) or 1 (minip)
  instead of nothing (with a ramp: nothing for mip, but the ramp's top,
  opaque, for minip); the CPU mapper and lacuna leave such pixels empty.
- iso (`--iso V[,V2..]`, normalised as TF values, at most 4): the first
  crossing of an iso value along the ray, opaque, lit with the Phong
  parameters above, coloured by the TF's colour at the value. GPU mapper
  only (vtkVolumeMapper ISOSURFACE_BLEND; the contour values go on the
  property's iso-surface values). Its surface opacity comes from the scalar
  opacity function at the value, so the iso property's opacity is a
  constant 1 (lacuna's surfaces are opaque); the crossing is not refined
  (lacuna bisects it) and it is lit at the first sample past it. Early ray
  termination does not apply (the first surface ends the ray); `--ert` is
  ignored.
- average: not offered. VTK's AVERAGE_INTENSITY_BLEND is an opacity-weighted
  mean shown as opaque grey, not lacuna's mean sample through the TF.

A mapper without the requested look is skipped, never imitated: the fixed-
point CPU mapper has no iso-surface blend (it would silently composite), so
`--mode iso` skips it with the note "no such mode" under `skipped` in the
JSON; when no requested mapper has the look the script exits 2.

VTK details that matter: vtkImageReader2 needs SetFileDimensionality(3)
(else it reads one 2-D slice) and SetFileLowerLeft(1) (else it flips y);
each mapper gets its own vtkVolumeProperty with gradient opacity disabled
(the fixed-point mapper attaches a default gradient-opacity function to the
property it renders, after which the GPU mapper computes gradients at every
sample, 3x slower).

Mappers (`--mapper`):
- cpu: vtkFixedPointVolumeRayCastMapper, multi-threaded software ray casting
  (15-bit fixed point). It skips samples in 4^3-voxel cells whose value range
  maps to zero opacity (its own empty-space skipping; there is no switch),
  and it always terminates composite rays early once the remaining
  transparency drops below 255/32767 (alpha > 0.9922): the check is a
  compiled-in macro (VTKKWRCHelper_CompositeColorAndCheckEarlyTermination)
  with no API, so `--ert off` cannot be honoured; the JSON says so. Modes:
  composite (shaded or not), mip, minip.
- gpu: vtkGPUVolumeRayCastMapper, GLSL ray casting; through OSMesa it runs
  on Mesa's llvmpipe, i.e. on the CPU cores too. Its shader terminates rays
  at alpha > 1 - 1/255 by default; `--ert off` (the default, as lacuna's
  benchmark) raises that threshold to 2 with a fragment-shader replacement of
  `//VTK::Termination::Dec`, so composite rays march to the box exit. Modes:
  composite (shaded or not), mip, minip, iso.

Timing: after an untimed render of view 0 (checked for coverage and saved
with `--png`, RGB over black, as rendered or with `--srgb` sRGB-encoded as
lacuna's PNGs are; for lit looks it also computes the CPU mapper's
gradients) and `--warmup` untimed views, each of `--frames` views
is timed as the wall time of renderWindow.Render() plus WaitForCompletion()
(glFinish, so llvmpipe has finished the frame when the clock stops; Render
alone returns a few per cent early). Printed to stdout as JSON: the look
(mode, shade, phong, iso, crop) and per mapper median_ms, min_ms, max_ms,
frames, frame_ms, coverage, ert, vtk_version, size, step, and threads (cpu)
or the OpenGL renderer (gpu); mappers without the look under `skipped`.
Errors go to stderr.

Coverage is the fraction of frame-0 pixels with alpha or luminance above
1/255. A peer that renders nothing is not timed: below `--min-coverage`
(default 0.001), or below half of `--expect-coverage X` (e.g. lacuna's own
coverage of the same view), it prints `error: ... rendered an empty frame`
and exits 1. Bad input, a look no requested mapper has, or a missing
dependency exits 2.
"""

import argparse
import ctypes
import json
import math
import os
import re
import statistics
import sys
import time

# Must be set before VTK creates a render window: the pip wheels pick the
# window class (X, EGL or OSMesa) at run time from it.
os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = "vtkOSOpenGLRenderWindow"

INSTALL_HINT = "install with: pip install vtk numpy; apt install libosmesa6"
# The names vtkOSOpenGLRenderWindow dlopens on Linux, in its order.
OSMESA_NAMES = ("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so")
LUT_SIZE = 1024  # lacuna's tf::LUT_SIZE
VISIBLE = 1.0 / 255.0  # coverage threshold on alpha / luminance
# lacuna's default colormap stops (src/tf.rs `colormap`).
COLOR_STOPS = (
    (0.0, (0.05, 0.03, 0.25)),
    (0.25, (0.30, 0.10, 0.55)),
    (0.5, (0.80, 0.25, 0.35)),
    (0.75, (0.98, 0.60, 0.15)),
    (1.0, (1.0, 0.95, 0.70)),
)
# Open SciVis type names -> (numpy dtype, vtkImageReader2 setter).
TYPES = {
    "uint8": ("<u1", "SetDataScalarTypeToUnsignedChar"),
    "int8": ("<i1", "SetDataScalarTypeToSignedChar"),
    "uint16": ("<u2", "SetDataScalarTypeToUnsignedShort"),
    "int16": ("<i2", "SetDataScalarTypeToShort"),
    "float32": ("<f4", "SetDataScalarTypeToFloat"),
    "float64": ("<f8", "SetDataScalarTypeToDouble"),
}
CPU_ERT_ALPHA = 1.0 - 255.0 / 32767.0  # fixed-point mapper, compiled in
GPU_ERT_ALPHA = 1.0 - 1.0 / 255.0  # GPU mapper's default g_opacityThreshold
MODES = ("composite", "mip", "minip", "iso")
MAX_ISO = 4  # lacuna's desc::mode::MAX_ISO
PHONG_DEFAULT = (0.1, 0.7, 0.2, 10.0)  # lacuna's and VTK's defaults
# The blend modes each mapper has, per look (vtkVolumeMapper setters).
BLEND = {
    "cpu": {"composite": "SetBlendModeToComposite", "mip": "SetBlendModeToMaximumIntensity",
            "minip": "SetBlendModeToMinimumIntensity"},
    "gpu": {"composite": "SetBlendModeToComposite", "mip": "SetBlendModeToMaximumIntensity",
            "minip": "SetBlendModeToMinimumIntensity", "iso": "SetBlendModeToIsoSurface"},
}
NO_SUCH_MODE = {
    ("cpu", "iso"): "no such mode: vtkFixedPointVolumeRayCastMapper has no iso-surface blend "
    "(it would composite instead)",
}
# Lit looks: the eye this many bounding-sphere radii from the centre, so the
# GPU mapper's headlight (at the eye position) is parallel to the view.
LIT_EYE_RADII = 1000.0


class Failure(Exception):
    """A one-line error for the user and the exit code that goes with it."""

    def __init__(self, message, code):
        super().__init__(message)
        self.code = code


def fail(message, code=2):
    raise Failure(message, code)


# ---------------------------------------------------------------- dependencies


def import_dependencies():
    """Imports numpy and VTK, checks OSMesa; returns (numpy, vtk namespace)."""
    try:
        import numpy
    except ImportError:
        fail(f"numpy is not installed; {INSTALL_HINT}")
    try:
        # vtkmodules, not `vtk`: this file is itself named vtk.py, and
        # `import vtk` from its directory would import the script.
        from vtkmodules import vtkCommonCore, vtkCommonDataModel, vtkImagingCore, vtkIOImage
        from vtkmodules import vtkRenderingCore, vtkRenderingVolume
        from vtkmodules import vtkRenderingOpenGL2  # noqa: F401  (OpenGL overrides)
        from vtkmodules import vtkRenderingVolumeOpenGL2  # noqa: F401
        from vtkmodules.util import numpy_support
    except ImportError as e:
        fail(f"cannot import VTK ({e}); {INSTALL_HINT}")
    version = vtkCommonCore.vtkVersion.GetVTKVersion()
    if int(version.split(".")[0]) < 9:
        fail(f"VTK {version} is too old (need 9.x); {INSTALL_HINT}")
    if not any(_loadable(name) for name in OSMESA_NAMES):
        fail(f"OSMesa (libOSMesa.so) not found; {INSTALL_HINT}")
    ns = argparse.Namespace(
        core=vtkCommonCore,
        data=vtkCommonDataModel,
        imaging=vtkImagingCore,
        io=vtkIOImage,
        rendering=vtkRenderingCore,
        volume=vtkRenderingVolume,
        numpy_support=numpy_support,
        version=version,
    )
    return numpy, ns


def _loadable(name):
    try:
        ctypes.CDLL(name)
        return True
    except OSError:
        return False


# --------------------------------------------------------------- command line


def parse_size(text):
    m = re.fullmatch(r"(\d+)x(\d+)", text)
    if not m or int(m[1]) == 0 or int(m[2]) == 0:
        raise argparse.ArgumentTypeError(f"'{text}' is not WxH with positive integers")
    return int(m[1]), int(m[2])


def parse_ramp(text):
    """lacuna's `ramp:LO:HI[:ALPHA]` -> (lo, hi, alpha)."""
    parts = text.split(":")
    if parts[0] != "ramp" or len(parts) not in (3, 4):
        raise argparse.ArgumentTypeError(f"'{text}': only ramp:LO:HI[:ALPHA] is supported")
    try:
        nums = [float(p) for p in parts[1:]]
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': LO, HI and ALPHA must be numbers")
    lo, hi = nums[0], nums[1]
    alpha = nums[2] if len(nums) == 3 else 1.0
    if not lo < hi:
        raise argparse.ArgumentTypeError(f"'{text}': LO must be below HI")
    if not 0.0 <= alpha <= 1.0:
        raise argparse.ArgumentTypeError(f"'{text}': ALPHA must be in [0, 1]")
    return lo, hi, alpha


def parse_tf(text):
    """A lacuna TF spec: ramp:LO:HI[:ALPHA] or a ParaView JSON export, as
    (spec, LUT) with lacuna's LUT of (v, r, g, b, a) over v in [0, 1]."""
    if text.lower().endswith(".json"):
        return text, json_lut(text)
    lo, hi, alpha = parse_ramp(text)
    return f"ramp:{lo:g}:{hi:g}:{alpha:g}", ramp_lut(lo, hi, alpha)


def parse_phong(text):
    """KA,KD,KS,N -> four floats (weights >= 0, shininess > 0)."""
    try:
        nums = [float(p) for p in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': expected KA,KD,KS,N numbers")
    if len(nums) != 4 or any(not math.isfinite(v) for v in nums):
        raise argparse.ArgumentTypeError(f"'{text}': expected KA,KD,KS,N (four finite numbers)")
    if min(nums[:3]) < 0 or nums[3] <= 0:
        raise argparse.ArgumentTypeError(f"'{text}': weights must be >= 0 and N > 0")
    return tuple(nums)


def parse_iso(text):
    """V[,V2..] normalised iso values (1 to MAX_ISO finite numbers)."""
    try:
        nums = [float(p) for p in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': expected V[,V2,...] numbers")
    if not 1 <= len(nums) <= MAX_ISO or any(not math.isfinite(v) for v in nums):
        raise argparse.ArgumentTypeError(f"'{text}': expected 1 to {MAX_ISO} finite values")
    return tuple(nums)


def parse_crop(text):
    """lacuna's X0:X1,Y0:Y1,Z0:Z1 (voxel coordinates) -> (x0, x1, y0, y1, z0, z1)."""
    axes = text.split(",")
    try:
        pairs = [tuple(float(v) for v in a.split(":")) for a in axes]
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': expected X0:X1,Y0:Y1,Z0:Z1 numbers")
    if len(pairs) != 3 or any(len(p) != 2 or not p[0] < p[1] for p in pairs):
        raise argparse.ArgumentTypeError(f"'{text}': expected X0:X1,Y0:Y1,Z0:Z1 with each low < high")
    return tuple(v for p in pairs for v in p)


def positive_float(text):
    v = float(text)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"'{text}' must be > 0")
    return v


def parse_args(argv):
    p = argparse.ArgumentParser(
        description="Time VTK's volume mappers (offscreen, OSMesa) on lacuna's benchmark work.",
        epilog="See the module docstring for what is reproduced and how.",
    )
    p.add_argument("volume", help="raw file named name_WxHxD_TYPE.raw (little-endian, x fastest); "
                   "A.raw+B.raw: channels, as lacuna joins them (VTK's independent components)")
    p.add_argument("--tf", action="append", type=parse_tf, metavar="ramp:LO:HI[:ALPHA]|TF.json",
                   help="lacuna transfer function over the normalised value (default ramp:0.3:0.6); "
                   "once per channel, or once for all")
    p.add_argument("--mode", default="composite", choices=MODES,
                   help="what each ray shows (default composite); iso needs --iso and the GPU mapper")
    p.add_argument("--iso", type=parse_iso, metavar="V[,V2..]",
                   help="iso values for --mode iso, normalised to [0, 1] as TF values")
    p.add_argument("--shade", default="off", choices=("off", "on"),
                   help="Blinn-Phong shading of composite frames under a headlight (default off); "
                   "iso surfaces are always lit")
    p.add_argument("--phong", default=PHONG_DEFAULT, type=parse_phong, metavar="KA,KD,KS,N",
                   help="ambient, diffuse, specular weights and shininess (default 0.1,0.7,0.2,10)")
    p.add_argument("--crop", type=parse_crop, metavar="X0:X1,Y0:Y1,Z0:Z1",
                   help="keep this box, in voxel coordinates (lacuna's --crop)")
    p.add_argument("--size", default=(512, 512), type=parse_size, metavar="WxH", help="default 512x512")
    p.add_argument("--step", default=0.5, type=positive_float, help="sample distance in voxels (default 0.5)")
    p.add_argument("--frames", default=6, type=int, help="timed views of the orbit (default 6)")
    p.add_argument("--warmup", default=1, type=int, help="untimed views before timing (default 1)")
    p.add_argument("--elevation", default=20.0, type=float, help="orbit elevation in degrees (default 20)")
    p.add_argument("--azimuth", default=0.0, type=float,
                   help="azimuth of view 0 in degrees (default 0, as lacuna's bench); "
                   "with --frames 1 the view of lacuna's `render --camera AZ,EL`")
    p.add_argument("--mapper", default="both", choices=("cpu", "gpu", "both"))
    p.add_argument("--ert", default="off", choices=("off", "on"),
                   help="early ray termination (default off, as lacuna's benchmark)")
    p.add_argument("--png", metavar="PATH",
                   help="save frame 0 as an RGB PNG over black "
                   "(with --mapper both: PATH-cpu.png and PATH-gpu.png)")
    p.add_argument("--srgb", action="store_true",
                   help="sRGB-encode the PNG's colours, as lacuna's PNGs are (VTK's, like lacuna's, "
                   "are linear; without it they are written as rendered)")
    p.add_argument("--expect-coverage", type=float, metavar="X",
                   help="expected coverage of frame 0 (e.g. lacuna's); below X/2 is an error")
    p.add_argument("--min-coverage", type=float, default=0.001,
                   help="coverage of frame 0 below which the peer counts as empty (default 0.001)")
    args = p.parse_args(argv)
    args.tf = args.tf or [parse_tf("ramp:0.3:0.6")]
    # A path that exists is one channel, '+' in its name or not.
    args.channels = [args.volume] if os.path.exists(args.volume) else args.volume.split("+")
    if len(args.channels) > 4:
        p.error("at most 4 channels (VTK's independent components)")
    if len(args.tf) not in (1, len(args.channels)):
        p.error(f"{len(args.tf)} --tf for {len(args.channels)} channels: give one, or one per channel")
    if len(args.channels) > 1 and (args.mode != "composite" or args.shade == "on"):
        p.error("several channels: unshaded composite only (lacuna shades one channel)")
    if args.frames < 1:
        p.error("--frames must be >= 1")
    if args.warmup < 0:
        p.error("--warmup must be >= 0")
    if args.mode == "iso" and args.iso is None:
        p.error("--mode iso needs --iso V[,V2,...]")
    if args.mode != "iso" and args.iso is not None:
        p.error("--iso needs --mode iso")
    if args.shade == "on" and args.mode in ("mip", "minip"):
        p.error(f"--shade on shades composite and iso frames, not {args.mode}")
    # Iso surfaces are always lit (lacuna's), composite ones when asked.
    args.lit = args.mode == "iso" or args.shade == "on"
    return args


# --------------------------------------------------------------------- volume


def raw_layout(path):
    """(dims, type name) from an Open SciVis name such as skull_256x256x256_uint8.raw."""
    name = os.path.basename(path)
    m = re.fullmatch(r".*_(\d+)x(\d+)x(\d+)_([a-z0-9]+)\.raw", name)
    if not m:
        fail(f"'{name}' is not named name_WxHxD_TYPE.raw")
    dims = tuple(int(m[i]) for i in (1, 2, 3))
    ty = m[4]
    if ty not in TYPES:
        fail(f"'{name}': voxel type '{ty}' is not one of {', '.join(TYPES)}")
    if 0 in dims:
        fail(f"'{name}' has a zero dimension")
    return dims, ty


def read_volume(vtk, np, path):
    """Reads the raw file with vtkImageReader2; returns (reader, dims, type, (min, max))."""
    dims, ty = raw_layout(path)
    dtype, setter = TYPES[ty]
    expected = dims[0] * dims[1] * dims[2] * np.dtype(dtype).itemsize
    try:
        size = os.path.getsize(path)
    except OSError as e:
        fail(f"cannot read '{path}': {e.strerror}")
    if size != expected:
        fail(f"'{path}' holds {size} bytes but {dims[0]}x{dims[1]}x{dims[2]} {ty} needs {expected}")
    reader = vtk.io.vtkImageReader2()
    reader.SetFileName(path)
    getattr(reader, setter)()
    reader.SetNumberOfScalarComponents(1)
    reader.SetDataByteOrderToLittleEndian()
    # One 3-D file, not a series of 2-D slices (the default reads one slice).
    reader.SetFileDimensionality(3)
    # The default (upper-left origin) flips y on read; lacuna does not.
    reader.SetFileLowerLeft(True)
    reader.SetDataExtent(0, dims[0] - 1, 0, dims[1] - 1, 0, dims[2] - 1)
    reader.SetDataSpacing(1.0, 1.0, 1.0)
    # Voxel i at i + 0.5: lacuna's voxel space, box [0, dims].
    reader.SetDataOrigin(0.5, 0.5, 0.5)
    reader.Update()
    values = vtk.numpy_support.vtk_to_numpy(reader.GetOutput().GetPointData().GetScalars())
    if values.size != dims[0] * dims[1] * dims[2]:
        fail(f"VTK read {values.size} voxels from '{path}', expected {dims[0] * dims[1] * dims[2]}")
    if values.dtype.kind == "f" and not np.isfinite(values).all():
        fail(f"'{path}' holds a value that is not a finite number")
    value_range = (float(values.min()), float(values.max()))
    return reader, dims, ty, value_range


def read_channels(vtk, np, paths):
    """Each channel's raw file (read_volume), several joined as components
    of one image (same dims, as lacuna requires); (source, dims, type,
    [range per channel])."""
    reads = [read_volume(vtk, np, p) for p in paths]
    dims, ty = reads[0][1], reads[0][2]
    for p, r in zip(paths[1:], reads[1:]):
        if r[1] != dims:
            fail(f"channel '{p}' is {r[1]}, the first channel {dims}")
        # vtkImageAppendComponents joins one scalar type only (lacuna widens).
        if r[2] != ty:
            fail(f"channel '{p}' is {r[2]}, the first channel {ty}: VTK joins one voxel type only")
    if len(reads) == 1:
        return reads[0][0], dims, ty, [reads[0][3]]
    join = vtk.imaging.vtkImageAppendComponents()
    for r in reads:
        join.AddInputConnection(r[0].GetOutputPort())
    join.Update()
    return join, dims, "+".join(r[2] for r in reads), [r[3] for r in reads]


# ----------------------------------------------------------- transfer function


def colormap(t):
    """lacuna's colormap (src/tf.rs)."""
    t = min(max(t, 0.0), 1.0)
    for (t0, c0), (t1, c1) in zip(COLOR_STOPS, COLOR_STOPS[1:]):
        if t <= t1:
            f = (t - t0) / (t1 - t0)
            return tuple(a + (b - a) * f for a, b in zip(c0, c1))
    return COLOR_STOPS[-1][1]


def ramp_lut(lo, hi, alpha):
    """lacuna's ramp LUT: LUT_SIZE entries (v, r, g, b, a) over v in [0, 1]."""
    lut = []
    for i in range(LUT_SIZE):
        v = i / (LUT_SIZE - 1)
        t = min(max((v - lo) / (hi - lo), 0.0), 1.0)
        lut.append((v, *colormap(v), alpha * t))
    return lut


def json_lut(path):
    """lacuna's LUT of a ParaView colormap export (src/tf.rs
    from_paraview_json): the RGBPoints' x range onto [0, 1], linear
    segments, opacity from Points or a linear ramp."""
    try:
        with open(path) as f:
            data = json.load(f)
    except (OSError, ValueError) as e:
        raise argparse.ArgumentTypeError(f"'{path}': {e}")
    data = data[0] if isinstance(data, list) else data
    rgb = data.get("RGBPoints")
    if not rgb or len(rgb) % 4:
        raise argparse.ArgumentTypeError(f"'{path}': no RGBPoints (x, r, g, b)*")
    op = data.get("Points")
    groups = lambda pts: [pts[i:i + 4] for i in range(0, len(pts), 4)]

    def interp(pts, x, ch):
        g = groups(pts)
        if x <= g[0][0]:
            return g[0][ch]
        for a, b in zip(g, g[1:]):
            if x <= b[0]:
                f = (x - a[0]) / (b[0] - a[0]) if b[0] > a[0] else 1.0
                return a[ch] + (b[ch] - a[ch]) * f
        return g[-1][ch]

    x0, x1 = rgb[0], rgb[-4]
    lut = []
    for i in range(LUT_SIZE):
        v = i / (LUT_SIZE - 1)
        x = x0 + (x1 - x0) * v
        a = interp(op, x, 1) if op else v
        lut.append((v, interp(rgb, x, 1), interp(rgb, x, 2), interp(rgb, x, 3), a))
    return lut


def raw_value(v, value_range):
    """A normalised value (TF and iso specs) in the volume's raw units."""
    vmin, vmax = value_range
    return vmin + v * (vmax - vmin)


def tf_functions(vtk, lut, value_range, iso):
    """A LUT over normalised values as VTK's colour and opacity functions
    over raw values."""
    vmin, vmax = value_range
    color = vtk.rendering.vtkColorTransferFunction()
    opacity = vtk.data.vtkPiecewiseFunction()
    # Iso surfaces are opaque in lacuna; VTK's iso blend takes a surface's
    # opacity from the scalar opacity function at the value: constant 1.
    if vmax > vmin:
        for v, r, g, b, a in lut:
            x = raw_value(v, value_range)
            color.AddRGBPoint(x, r, g, b)
            opacity.AddPoint(x, 1.0 if iso else a)
    else:
        # lacuna maps a constant volume to v = 0.
        _, r, g, b, a = lut[0]
        color.AddRGBPoint(vmin, r, g, b)
        opacity.AddPoint(vmin, 1.0 if iso else a)
    return color, opacity


def volume_property(vtk, tfs, value_ranges, args):
    """The lacuna TFs (one per channel, or one for all) and look as a
    vtkVolumeProperty over raw values; several channels as independent
    components."""
    iso = args.mode == "iso"
    prop = vtk.rendering.vtkVolumeProperty()
    prop.SetIndependentComponents(True)  # VTK's default; several channels are independent
    for c, value_range in enumerate(value_ranges):
        color, opacity = tf_functions(vtk, tfs[min(c, len(tfs) - 1)][1], value_range, iso)
        prop.SetColor(c, color)
        prop.SetScalarOpacity(c, opacity)
        prop.SetScalarOpacityUnitDistance(c, 1.0)  # alpha per voxel of path length
    prop.SetInterpolationTypeToLinear()  # trilinear, then classify
    if args.lit:
        ka, kd, ks, n = args.phong
        prop.ShadeOn()
        prop.SetAmbient(ka)
        prop.SetDiffuse(kd)
        prop.SetSpecular(ks)
        prop.SetSpecularPower(n)
    else:
        prop.ShadeOff()
    if iso:
        for i, v in enumerate(args.iso):
            prop.GetIsoSurfaceValues().SetValue(i, raw_value(v, value_ranges[0]))
    # No gradient-magnitude opacity, as lacuna. Explicitly: the fixed-point
    # mapper calls GetGradientOpacity(), which attaches a default (constant 1)
    # function, and a GPU mapper seeing one computes a gradient at every
    # sample (measured 3x slower).
    prop.DisableGradientOpacityOn()
    return prop


# --------------------------------------------------------------------- camera


def orbit_view(dims, width, height, azimuth, elevation, eye_radii=None):
    """lacuna's orthographic orbit camera (src/render/camera.rs), spacing 1.

    Returns (focal point, position, view up, parallel scale). The eye is 1
    voxel outside the bounding sphere (lacuna's), or `eye_radii` bounding-
    sphere radii from the centre (the image is the same: orthographic).
    """
    centre = [d / 2.0 for d in dims]
    radius = sum(c * c for c in centre) ** 0.5
    sa, ca = sincos_deg(azimuth)
    se, ce = sincos_deg(elevation)
    to_eye = (ce * sa, se, ce * ca)
    forward = tuple(-c for c in to_eye)
    right = (ca, 0.0, -sa)
    up = cross(right, forward)
    half = [0.0, 0.0]
    for i in range(8):
        corner = [centre[a] if (i >> a) & 1 else -centre[a] for a in range(3)]
        half[0] = max(half[0], abs(dot(corner, right)))
        half[1] = max(half[1], abs(dot(corner, up)))
    pixel = max(2.0 * half[0] / width, 2.0 * half[1] / height)
    distance = radius + 1.0 if eye_radii is None else radius * eye_radii
    position = tuple(c + e * distance for c, e in zip(centre, to_eye))
    return tuple(centre), position, up, pixel * height / 2.0


def sincos_deg(deg):
    """(sin, cos), exact at multiples of 90 degrees as lacuna's."""
    quarter = deg / 90.0
    if quarter == int(quarter):
        return ((0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0))[int(quarter) % 4]
    r = math.radians(deg)
    return math.sin(r), math.cos(r)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


# ---------------------------------------------------------------------- render


def make_mapper(vtk, kind, reader, step, ert, volume, mode="composite"):
    """The mapper (in the blend mode of `mode`) and what it does with early
    ray termination."""
    if kind == "cpu":
        mapper = vtk.volume.vtkFixedPointVolumeRayCastMapper()
        mapper.SetAutoAdjustSampleDistances(0)
        mapper.SetSampleDistance(step)
        mapper.SetImageSampleDistance(1.0)
    else:
        mapper = vtk.volume.vtkGPUVolumeRayCastMapper()
        mapper.SetAutoAdjustSampleDistances(0)
        mapper.SetSampleDistance(step)
        mapper.SetUseJittering(0)
    mapper.SetInputConnection(reader.GetOutputPort())
    getattr(mapper, BLEND[kind][mode])()

    if mode != "composite":
        ert_info = {
            "requested": ert,
            "effective": "n/a",
            "note": ("the first surface ends an iso ray (opaque); the termination threshold is "
                     "left at the mapper's default") if mode == "iso"
            else f"{mode} accumulates no opacity, so there is nothing to terminate on",
        }
    elif kind == "cpu":
        ert_info = {
            "requested": ert,
            "effective": "on",
            "alpha": round(CPU_ERT_ALPHA, 6),
            "note": "vtkFixedPointVolumeRayCastMapper always stops a ray once its remaining "
            "transparency is below 255/32767 (compiled-in macro, no API to turn it off)"
            + ("; --ert off cannot be honoured" if ert == "off" else ""),
        }
    elif ert == "off":
        # Replace the declaration of the termination threshold before the
        # mapper's own substitutions: alpha never exceeds 2.
        volume.GetShaderProperty().AddFragmentShaderReplacement(
            "//VTK::Termination::Dec", True,
            "const float g_opacityThreshold = 2.0; // lacuna peer: no early ray termination", False)
        ert_info = {
            "requested": "off",
            "effective": "off",
            "note": "g_opacityThreshold raised to 2 by a fragment-shader replacement of "
            "//VTK::Termination::Dec",
        }
    else:
        ert_info = {
            "requested": "on",
            "effective": "on",
            "alpha": round(GPU_ERT_ALPHA, 6),
            "note": "the GPU mapper's default shader stops at alpha > 1 - 1/255",
        }
    return mapper, ert_info


def frame_rgba(vtk, window):
    """The window's RGBA pixels as a (height, width, 4) uint8 array (row 0 at the bottom)."""
    grab = vtk.rendering.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGBA()
    grab.ReadFrontBufferOff()
    grab.Update()
    image = grab.GetOutput()
    w, h, _ = image.GetDimensions()
    pixels = vtk.numpy_support.vtk_to_numpy(image.GetPointData().GetScalars())
    return pixels.reshape(h, w, 4).copy()


def srgb_encode(np, linear):
    """IEC 61966-2-1 encoding of linear values in [0, 1] (lacuna's srgb_encode)."""
    linear = np.clip(linear, 0.0, 1.0)
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * np.power(linear, 1.0 / 2.4) - 0.055)


def write_png(vtk, np, rgba, path, srgb):
    """Frame-0 RGB (row 0 at the bottom, as VTK's) as an 8-bit PNG, optionally sRGB-encoded."""
    rgb = rgba[..., :3]
    if srgb:
        rgb = (srgb_encode(np, rgb / 255.0) * 255.0 + 0.5).astype(np.uint8)
    h, w, _ = rgb.shape
    image = vtk.data.vtkImageData()
    image.SetDimensions(w, h, 1)
    image.GetPointData().SetScalars(vtk.numpy_support.numpy_to_vtk(
        np.ascontiguousarray(rgb).reshape(-1, 3), deep=True))
    writer = vtk.io.vtkPNGWriter()
    writer.SetFileName(path)
    writer.SetInputData(image)
    writer.Write()


def coverage(np, rgba):
    """Fraction of pixels with alpha or luminance (max of RGB) above 1/255."""
    limit = VISIBLE * 255.0
    visible = (rgba[..., 3] > limit) | (rgba[..., :3].max(axis=-1) > limit)
    return float(visible.mean())


def run_mapper(vtk, np, kind, reader, dims, args, value_range, png_path):
    width, height = args.size
    volume = vtk.rendering.vtkVolume()
    # A property of its own: mappers add state to the one they render.
    tf_prop = volume_property(vtk, args.tf, value_range, args)  # value_range: one per channel
    volume.SetProperty(tf_prop)
    mapper, ert_info = make_mapper(vtk, kind, reader, args.step, args.ert, volume, args.mode)
    if args.crop:
        # World coordinates are lacuna's voxel coordinates (origin 0.5, spacing 1).
        mapper.SetCropping(1)
        mapper.SetCroppingRegionPlanes(*args.crop)
        mapper.SetCroppingRegionFlagsToSubVolume()
    volume.SetMapper(mapper)

    renderer = vtk.rendering.vtkRenderer()
    renderer.SetBackground(0.0, 0.0, 0.0)
    renderer.SetBackgroundAlpha(0.0)
    renderer.AddVolume(volume)
    if args.lit:
        # The headlight VTK's renderer would create by itself (white,
        # intensity 1, at the camera, following it), with a white ambient
        # colour: the CPU mapper's ambient term is KA times the light's
        # ambient colour (black by default); the GPU mapper's is KA as is.
        light = vtk.rendering.vtkLight()
        light.SetLightTypeToHeadlight()
        light.SetAmbientColor(1.0, 1.0, 1.0)
        light.SetDiffuseColor(1.0, 1.0, 1.0)
        light.SetSpecularColor(1.0, 1.0, 1.0)
        light.SetIntensity(1.0)
        renderer.AddLight(light)
        renderer.TwoSidedLightingOn()
    window = vtk.rendering.vtkRenderWindow()
    if window.GetClassName() != "vtkOSOpenGLRenderWindow":
        fail(f"this VTK build ({vtk.version}) does not render through OSMesa "
             f"(got {window.GetClassName()}); {INSTALL_HINT}")
    window.SetOffScreenRendering(1)
    window.SetAlphaBitPlanes(1)
    window.SetMultiSamples(0)
    window.SetSize(width, height)
    window.AddRenderer(renderer)
    camera = renderer.GetActiveCamera()
    camera.ParallelProjectionOn()

    def show(view):
        azimuth = args.azimuth + 360.0 * (view % args.frames) / args.frames
        focal, position, up, scale = orbit_view(dims, width, height, azimuth, args.elevation,
                                                LIT_EYE_RADII if args.lit else None)
        camera.SetFocalPoint(*focal)
        camera.SetPosition(*position)
        camera.SetViewUp(*up)
        camera.SetParallelScale(scale)
        renderer.ResetCameraClippingRange()

    if kind == "gpu":
        window.Render()  # create the context before asking about support
        if not mapper.IsRenderSupported(window, tf_prop):
            fail("vtkGPUVolumeRayCastMapper is not supported by this OpenGL context")

    # Frame 0, untimed: the empty-frame check and the PNG.
    show(0)
    window.Render()
    window.WaitForCompletion()
    rgba = frame_rgba(vtk, window)
    covered = coverage(np, rgba)
    name = mapper.GetClassName()
    if covered < args.min_coverage:
        fail(f"{name} rendered an empty frame (coverage {covered:.5f} < {args.min_coverage})", 1)
    if args.expect_coverage is not None and covered < 0.5 * args.expect_coverage:
        fail(f"{name} rendered an empty frame (coverage {covered:.5f}, "
             f"expected about {args.expect_coverage})", 1)
    if png_path:
        # RGB as rendered over black (VTK's colours are premultiplied by
        # alpha, as lacuna's EXR; a PNG's alpha is straight, so it is dropped).
        write_png(vtk, np, rgba, png_path, args.srgb)

    for view in range(args.warmup):
        show(view)
        window.Render()
    window.WaitForCompletion()

    times = []
    for view in range(args.frames):
        show(view)
        start = time.perf_counter()
        window.Render()
        window.WaitForCompletion()
        times.append((time.perf_counter() - start) * 1000.0)

    record = {
        "mapper": name,
        "median_ms": round(statistics.median(times), 3),
        "min_ms": round(min(times), 3),
        "max_ms": round(max(times), 3),
        "frames": len(times),
        "frame_ms": [round(t, 3) for t in times],
        "coverage": round(covered, 6),
        "ert": ert_info,
        "vtk_version": vtk.version,
        "size": [width, height],
        "step": args.step,
    }
    if kind == "cpu":
        record["threads"] = mapper.GetNumberOfThreads()
    else:
        record["opengl"] = opengl_renderer(window)
    window.Finalize()
    return record


def opengl_renderer(window):
    """The 'OpenGL renderer string' line of the window's capabilities."""
    for line in (window.ReportCapabilities() or "").splitlines():
        if line.startswith("OpenGL renderer string:"):
            return line.split(":", 1)[1].strip()
    return "unknown"


def main(argv):
    args = parse_args(argv)
    try:
        np, vtk = import_dependencies()
        # VTK's warnings go to stderr; errors end in a Failure below.
        reader, dims, ty, value_range = read_channels(vtk, np, args.channels)
        kinds = ("cpu", "gpu") if args.mapper == "both" else (args.mapper,)
        skipped = {k: NO_SUCH_MODE[(k, args.mode)] for k in kinds if (k, args.mode) in NO_SUCH_MODE}
        if len(skipped) == len(kinds):
            fail(f"--mode {args.mode}: " + "; ".join(skipped.values()))
        mappers = {}
        for kind in kinds:
            if kind in skipped:
                print(f"note: {kind} mapper skipped: {skipped[kind]}", file=sys.stderr)
                continue
            png = args.png
            if png and args.mapper == "both":
                root, ext = os.path.splitext(png)
                png = f"{root}-{kind}{ext or '.png'}"
            mappers[kind] = run_mapper(vtk, np, kind, reader, dims, args, value_range, png)
    except Failure as e:
        print(f"error: {e}", file=sys.stderr)
        return e.code
    result = {
        "peer": "vtk",
        "vtk_version": vtk.version,
        "volume": args.volume,
        "dims": list(dims),
        "type": ty,
        "value_range": list(value_range[0]) if len(value_range) == 1 else [list(r) for r in value_range],
        "tf": " | ".join(spec for spec, _ in args.tf),
        "mode": args.mode,
        "shade": args.mode == "composite" and args.shade == "on",
        "lit": args.lit,
        "phong": list(args.phong) if args.lit else None,
        "light": "headlight" if args.lit else None,
        "iso": list(args.iso) if args.iso else None,
        "crop": list(args.crop) if args.crop else None,
        "camera": f"ortho orbit, elevation {args.elevation:g}, "
        f"azimuth {args.azimuth:g} + 360*i/{args.frames}",
        "size": list(args.size),
        "step": args.step,
        "warmup": args.warmup,
        "cpus": os.cpu_count(),
        "mappers": mappers,
        "skipped": skipped,
    }
    json.dump(result, sys.stdout, indent=2)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
