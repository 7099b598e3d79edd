#!/usr/bin/env python3
"""Peer benchmark: render lacuna's benchmark work with VTK on the CPU.

Renders a raw volume the way `lacuna bench` does (orthographic orbit camera
zoomed so the projected volume box fills the viewport, emission-absorption,
post-classification, no shading, lacuna's `ramp` transfer function, the same
sample distance) with VTK's two volume mappers, offscreen through OSMesa, and
prints per-frame wall times as JSON. It is what a user without a GPU would
reach for, so lacuna's docs can say how they compare.

Usage:
    python3 bench/peers/vtk.py VOLUME.raw [--tf ramp:LO:HI[:ALPHA]]
        [--size 512x512] [--step 0.5] [--frames 6] [--warmup 1]
        [--elevation 20] [--azimuth 0] [--mapper cpu|gpu|both] [--ert off|on]
        [--png frame0.png] [--expect-coverage X] [--min-coverage 0.001]

    python3 bench/peers/vtk.py /data/skull_256x256x256_uint8.raw \\
        --tf ramp:0.3:0.6 --mapper both --frames 6 --png /tmp/skull.png

Requirements: numpy and VTK 9.x from pip (`pip install vtk numpy`), and
Mesa's OSMesa (`apt install libosmesa6`). The script selects VTK's OSMesa
window itself (VTK_DEFAULT_OPENGL_WINDOW=vtkOSOpenGLRenderWindow, honoured by
the pip wheels since VTK 9.4); no display is needed. Missing either prints
one `error:` line and exits 2.

What it reproduces from lacuna (src/render/camera.rs, src/tf.rs,
src/volume/mod.rs, glsl/common/lattice.glsl):

- Input: an Open SciVis raw file `name_WxHxD_TYPE.raw`, little-endian, x
  fastest, spacing 1. TYPE: uint8, int8, uint16, int16, float32, float64.
  Voxel i sits at i + 0.5, so the volume box is [0, W] x [0, H] x [0, D] as in
  lacuna's voxel space.
- Normalisation: lacuna maps every voxel type linearly over the volume's own
  value range, v = (raw - min) / (max - min) (for uint8 that is not raw/255
  unless the data spans 0..255). The transfer function is therefore placed
  over [min, max] in raw units.
- Transfer function `ramp:LO:HI[:ALPHA]`: lacuna's 1024-entry LUT over
  v in [0, 1]: colour = its violet-orange-yellow colormap at v, alpha =
  ALPHA * clamp((v - LO) / (HI - LO), 0, 1) per voxel of path length. Every
  LUT entry becomes a point of the vtkColorTransferFunction and the
  vtkPiecewiseFunction (linear interpolation between entries, as lacuna's
  lookup). The opacity unit distance is 1 voxel, and both mappers correct
  opacity for the sample distance as lacuna does.
- Camera: azimuth and elevation about the volume centre, y up; view i of N
  is at azimuth `--azimuth` + 360 * i / N (the bench orbit starts at 0) and
  `--elevation` (default 20, as bench/quick.toml and bench/paper.toml).
  Orthographic, with the parallel scale lacuna computes: the projected box
  corners fit the viewport. Row 0 of the PNG is the top, as in lacuna's EXR.
- `--step S`: sample distance S voxels along the ray (spacing 1, so world
  units), fixed: automatic sample-distance adjustment is off for both mappers
  and the CPU mapper casts one ray per pixel (image sample distance 1).

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
  and it always terminates rays early once the remaining transparency drops
  below 255/32767 (alpha > 0.9922): the check is a compiled-in macro
  (VTKKWRCHelper_CompositeColorAndCheckEarlyTermination) with no API, so
  `--ert off` cannot be honoured; the JSON says so.
- gpu: vtkGPUVolumeRayCastMapper, GLSL ray casting; through OSMesa it runs
  on Mesa's llvmpipe, i.e. on the CPU cores too. Its shader terminates rays
  at alpha > 1 - 1/255 by default; `--ert off` (the default, as lacuna's
  benchmark) raises that threshold to 2 with a fragment-shader replacement of
  `//VTK::Termination::Dec`, so rays march to the box exit.

Timing: after an untimed render of view 0 (checked for coverage and saved
with `--png`, RGB over black) and `--warmup` untimed views, each of
`--frames` views is timed as the wall time of renderWindow.Render() plus
WaitForCompletion() (glFinish, so llvmpipe has finished the frame when the
clock stops; Render alone returns a few per cent early). Printed to stdout
as JSON: per mapper median_ms, min_ms, max_ms, frames, frame_ms, coverage,
ert, vtk_version, size, step, and threads (cpu) or the OpenGL renderer (gpu).
Errors go to stderr.

Coverage is the fraction of frame-0 pixels with alpha or luminance above
1/255. A peer that renders nothing is not timed: below `--min-coverage`
(default 0.001), or below half of `--expect-coverage X` (e.g. lacuna's own
coverage of the same view), it prints `error: ... rendered an empty frame`
and exits 1. Bad input or a missing dependency exits 2.
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
    p.add_argument("volume", help="raw file named name_WxHxD_TYPE.raw (little-endian, x fastest)")
    p.add_argument("--tf", default="ramp:0.3:0.6", type=parse_ramp, metavar="ramp:LO:HI[:ALPHA]",
                   help="lacuna transfer function over the normalised value (default ramp:0.3:0.6)")
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
    p.add_argument("--expect-coverage", type=float, metavar="X",
                   help="expected coverage of frame 0 (e.g. lacuna's); below X/2 is an error")
    p.add_argument("--min-coverage", type=float, default=0.001,
                   help="coverage of frame 0 below which the peer counts as empty (default 0.001)")
    args = p.parse_args(argv)
    if args.frames < 1:
        p.error("--frames must be >= 1")
    if args.warmup < 0:
        p.error("--warmup must be >= 0")
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


def volume_property(vtk, tf, value_range):
    """The lacuna TF as VTK colour and opacity functions over raw values."""
    vmin, vmax = value_range
    color = vtk.rendering.vtkColorTransferFunction()
    opacity = vtk.data.vtkPiecewiseFunction()
    lut = ramp_lut(*tf)
    if vmax > vmin:
        for v, r, g, b, a in lut:
            x = vmin + v * (vmax - vmin)
            color.AddRGBPoint(x, r, g, b)
            opacity.AddPoint(x, a)
    else:
        # lacuna maps a constant volume to v = 0.
        _, r, g, b, a = lut[0]
        color.AddRGBPoint(vmin, r, g, b)
        opacity.AddPoint(vmin, a)
    prop = vtk.rendering.vtkVolumeProperty()
    prop.SetColor(color)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(1.0)  # alpha per voxel of path length
    prop.SetInterpolationTypeToLinear()  # trilinear, then classify
    prop.ShadeOff()
    # No gradient-magnitude opacity, as lacuna. Explicitly: the fixed-point
    # mapper calls GetGradientOpacity(), which attaches a default (constant 1)
    # function, and a GPU mapper seeing one computes a gradient at every
    # sample (measured 3x slower).
    prop.DisableGradientOpacityOn()
    return prop


# --------------------------------------------------------------------- camera


def orbit_view(dims, width, height, azimuth, elevation):
    """lacuna's orthographic orbit camera (src/render/camera.rs), spacing 1.

    Returns (focal point, position, view up, parallel scale).
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
    position = tuple(c + e * (radius + 1.0) for c, e in zip(centre, to_eye))
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


def make_mapper(vtk, kind, reader, step, ert, volume):
    """The mapper and what it does with early ray termination."""
    if kind == "cpu":
        mapper = vtk.volume.vtkFixedPointVolumeRayCastMapper()
        mapper.SetAutoAdjustSampleDistances(0)
        mapper.SetSampleDistance(step)
        mapper.SetImageSampleDistance(1.0)
        ert_info = {
            "requested": ert,
            "effective": "on",
            "alpha": round(CPU_ERT_ALPHA, 6),
            "note": "vtkFixedPointVolumeRayCastMapper always stops a ray once its remaining "
            "transparency is below 255/32767 (compiled-in macro, no API to turn it off)"
            + ("; --ert off cannot be honoured" if ert == "off" else ""),
        }
    else:
        mapper = vtk.volume.vtkGPUVolumeRayCastMapper()
        mapper.SetAutoAdjustSampleDistances(0)
        mapper.SetSampleDistance(step)
        mapper.SetUseJittering(0)
        if ert == "off":
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
    mapper.SetInputConnection(reader.GetOutputPort())
    mapper.SetBlendModeToComposite()
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
    return pixels.reshape(h, w, 4).copy(), grab


def coverage(np, rgba):
    """Fraction of pixels with alpha or luminance (max of RGB) above 1/255."""
    limit = VISIBLE * 255.0
    visible = (rgba[..., 3] > limit) | (rgba[..., :3].max(axis=-1) > limit)
    return float(visible.mean())


def run_mapper(vtk, np, kind, reader, dims, args, value_range, png_path):
    width, height = args.size
    volume = vtk.rendering.vtkVolume()
    # A property of its own: mappers add state to the one they render.
    tf_prop = volume_property(vtk, args.tf, value_range)
    volume.SetProperty(tf_prop)
    mapper, ert_info = make_mapper(vtk, kind, reader, args.step, args.ert, volume)
    volume.SetMapper(mapper)

    renderer = vtk.rendering.vtkRenderer()
    renderer.SetBackground(0.0, 0.0, 0.0)
    renderer.SetBackgroundAlpha(0.0)
    renderer.AddVolume(volume)
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
        focal, position, up, scale = orbit_view(dims, width, height, azimuth, args.elevation)
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
    rgba, grab = frame_rgba(vtk, window)
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
        rgb = vtk.imaging.vtkImageExtractComponents()
        rgb.SetInputConnection(grab.GetOutputPort())
        rgb.SetComponents(0, 1, 2)
        writer = vtk.io.vtkPNGWriter()
        writer.SetFileName(png_path)
        writer.SetInputConnection(rgb.GetOutputPort())
        writer.Write()

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
        reader, dims, ty, value_range = read_volume(vtk, np, args.volume)
        kinds = ("cpu", "gpu") if args.mapper == "both" else (args.mapper,)
        mappers = {}
        for kind in kinds:
            png = args.png
            if png and len(kinds) > 1:
                root, ext = os.path.splitext(png)
                png = f"{root}-{kind}{ext or '.png'}"
            mappers[kind] = run_mapper(vtk, np, kind, reader, dims, args, value_range, png)
    except Failure as e:
        print(f"error: {e}", file=sys.stderr)
        return e.code
    lo, hi, alpha = args.tf
    result = {
        "peer": "vtk",
        "vtk_version": vtk.version,
        "volume": args.volume,
        "dims": list(dims),
        "type": ty,
        "value_range": list(value_range),
        "tf": f"ramp:{lo:g}:{hi:g}:{alpha:g}",
        "camera": f"ortho orbit, elevation {args.elevation:g}, "
        f"azimuth {args.azimuth:g} + 360*i/{args.frames}",
        "size": list(args.size),
        "step": args.step,
        "warmup": args.warmup,
        "cpus": os.cpu_count(),
        "mappers": mappers,
    }
    json.dump(result, sys.stdout, indent=2)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
