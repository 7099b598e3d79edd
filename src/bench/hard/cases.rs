//! The hard cases and the looks each is rendered in (DESIGN, "Hard
//! cases"; README, "Looks").

use crate::error::Result;
use crate::render::{Camera, FrameDesc, LookSpec, Projection, Rays};
use crate::volume::{LoadOptions, StepNorm, VoxelData, VoxelType};
use crate::Volume;

/// One hard case of `--suite hard`: a volume, a transfer function and the
/// views every structure must render as naive does.
pub struct HardCase {
    pub name: &'static str,
    pub volume: Volume,
    pub tf: &'static str,
    /// The views (each rendered under every sample filter the volume's
    /// format supports).
    pub views: Vec<FrameDesc>,
    /// The iso value of the iso looks: one the data crosses.
    pub iso: &'static str,
    /// What every look of the case adds (its clip planes, crop box).
    pub look: LookSpec,
}

/// A look every case is rendered in: its name, its options, and whether it
/// is rendered under every filter (else the manual filter only: the filter
/// is orthogonal to the look, and the composite look checks both).
pub struct HardLook {
    pub name: &'static str,
    pub spec: LookSpec,
    pub all_filters: bool,
}

/// The looks: plain composite; shaded composite with a fixed light,
/// gradient opacity and jitter; mip; minip; average (no structure skips in
/// it: each is marched naively, nothing to compare); iso with jitter.
pub fn looks(iso: &str) -> Vec<HardLook> {
    let on = Some(true);
    let text = |s: &str| Some(s.to_string());
    let look = |name, spec, all_filters| HardLook {
        name,
        spec,
        all_filters,
    };
    vec![
        look("composite", LookSpec::default(), true),
        look(
            "shaded, jittered",
            LookSpec {
                shade: on,
                light: text("60,30"),
                gradient_opacity: text("0:0.08"),
                jitter: on,
                ..LookSpec::default()
            },
            false,
        ),
        look(
            "mip",
            LookSpec {
                mode: text("mip"),
                ..LookSpec::default()
            },
            false,
        ),
        look(
            "minip",
            LookSpec {
                mode: text("minip"),
                ..LookSpec::default()
            },
            false,
        ),
        look(
            "average",
            LookSpec {
                mode: text("average"),
                ..LookSpec::default()
            },
            false,
        ),
        look(
            "iso, jittered",
            LookSpec {
                mode: text("iso"),
                iso: text(iso),
                jitter: on,
                ..LookSpec::default()
            },
            false,
        ),
    ]
}

/// An orbit camera view (orthographic or perspective).
pub fn cam(size: u32, az: f64, el: f64, projection: Projection, step: f32, ert: Option<f32>) -> Result<FrameDesc> {
    FrameDesc::builder(size, size)
        .orbit(az, el, projection)
        .step(step)
        .ert(ert)
        .build()
}

const ORTHO: Projection = Projection::Orthographic;

/// Orthographic rays laid out by hand: pixel (i, j) starts at start + i * du
/// + j * dv and travels along dir.
pub fn lattice(size: u32, start: [f32; 3], du: [f32; 3], dv: [f32; 3], dir: [f32; 3], step: f32) -> Result<FrameDesc> {
    let base = [0, 1, 2].map(|a| start[a] - 0.5 * (du[a] + dv[a]));
    FrameDesc::builder(size, size)
        .camera(Camera::Rays(Rays::orthographic(base, du, dv, dir)))
        .step(step)
        .build()
}

/// 33x33 rays along +z through x, y = 0 .. 32: through brick faces at
/// multiples of 8 and edges where both are.
pub fn along_z_through_brick_faces() -> Result<FrameDesc> {
    lattice(
        33,
        [0.0, 0.0, -5.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        0.5,
    )
}

fn gen(spec: &str) -> Result<Volume> {
    Volume::load(spec, &LoadOptions::default())
}

/// `spec`'s volume as float data without data in places: NaN in a ball at
/// the centre, +inf on the plane x = 1, -inf on y = 2.
pub fn masked(spec: &str) -> Result<Volume> {
    let v = gen(spec)?;
    let [w, h, d] = v.dims;
    let r = w.min(h).min(d) as f32 / 4.0;
    let mut data = Vec::with_capacity(v.voxel_count() as usize);
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                let p = [
                    x as f32 + 0.5 - w as f32 / 2.0,
                    y as f32 + 0.5 - h as f32 / 2.0,
                    z as f32 + 0.5 - d as f32 / 2.0,
                ];
                let value = match (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] < r * r, x, y) {
                    (true, _, _) => f32::NAN,
                    (_, 1, _) => f32::INFINITY,
                    (_, _, 2) => f32::NEG_INFINITY,
                    _ => v.value(x, y, z),
                };
                data.push(value);
            }
        }
    }
    Volume::new(
        format!("masked {spec}"),
        v.dims,
        v.spacing,
        VoxelType::F32,
        VoxelData::F32(data),
    )
}

/// Three steps of a float time series on 40^3, normalised as step 0 (a
/// ball of values 0 to 1 inside one brick): step 1 holds only values below
/// the cases' ramp (nothing visible), step 2 a ball centred on a brick
/// corner, its peak beyond step 0's range (it clamps).
pub fn series_steps() -> Result<[Volume; 3]> {
    let n = 40u32;
    let ball = |centre: f32, radius: f32, peak: f32, floor: f32| -> Result<Volume> {
        let mut data = Vec::with_capacity((n * n * n) as usize);
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let r2 = [x, y, z].map(|c| (c as f32 - centre).powi(2)).iter().sum::<f32>();
                    data.push(floor + peak * (1.0 - r2.sqrt() / radius).max(0.0));
                }
            }
        }
        Volume::new("ball series", [n; 3], [1.0; 3], VoxelType::F32, VoxelData::F32(data))
    };
    let first = ball(4.0, 3.5, 1.0, 0.0)?;
    let norm = StepNorm::of(&first);
    let mut quiet = ball(20.0, 12.0, 0.15, 0.05)?;
    norm.apply(&mut quiet, "step 1")?;
    let mut moved = ball(16.0, 6.0, 1.5, 0.0)?;
    norm.apply(&mut moved, "step 2")?;
    Ok([first, quiet, moved])
}

/// The cases, at sizes a CPU driver renders in seconds.
pub fn cases() -> Result<Vec<HardCase>> {
    let persp = |d: Option<f64>, fov: f64| Projection::Perspective {
        fov_deg: fov,
        distance: d,
    };
    let mut dot = vec![0u8; 40 * 40 * 40];
    dot[16 + 40 * (16 + 40 * 16)] = 255;
    let halves: Vec<u8> = (0..24 * 24 * 24).map(|i| if (i % 24) < 12 { 0 } else { 255 }).collect();
    let [_, quiet, moved] = series_steps()?;
    let long: Vec<u8> = (0..4 * 4 * 3000)
        .map(|i| if (i / 16) % 97 < 3 { 255 } else { 0 })
        .collect();
    Ok(vec![
        HardCase {
            name: "rays parallel to an axis",
            volume: gen("turbulence:33x29x31")?,
            tf: "ramp:0.5:1:0.3",
            views: vec![
                cam(32, 0.0, 0.0, ORTHO, 0.5, None)?,
                cam(32, 90.0, 0.0, ORTHO, 0.5, None)?,
                cam(32, 0.0, 90.0, ORTHO, 0.5, None)?,
            ],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "rays through brick faces and edges",
            volume: gen("turbulence:32")?,
            tf: "ramp:0.55:1:0.5",
            views: vec![along_z_through_brick_faces()?],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "rays through brick corners",
            volume: gen("turbulence:32")?,
            tf: "band:0.7:1",
            views: vec![lattice(
                17,
                [-4.0, -4.0, -4.0],
                [2.0, -2.0, 0.0],
                [1.0, 1.0, -2.0],
                [1.0, 1.0, 1.0],
                0.5,
            )?],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "grazing rays",
            volume: gen("turbulence:32")?,
            tf: "ramp:0.55:1:0.5",
            views: vec![
                lattice(
                    33,
                    [40.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                    [-1.0, 0.0, 0.0],
                    1.0,
                )?,
                lattice(
                    33,
                    [8.0, -3.0, 0.0],
                    [0.0, 0.0, 1.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 1.0],
                    0.5,
                )?,
            ],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "camera inside the volume",
            volume: gen("menger:27")?,
            tf: "ramp:0.3:1:0.5",
            views: vec![cam(32, 10.0, 5.0, persp(Some(0.1), 70.0), 0.5, None)?],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "camera inside an empty region",
            volume: gen("shells:48")?,
            tf: "ramp:0.2:1:0.8",
            views: vec![
                cam(32, 0.0, 0.0, persp(Some(0.0), 90.0), 0.5, None)?,
                cam(32, 33.0, 12.0, persp(Some(0.0), 90.0), 0.3, None)?,
            ],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "dims not multiples of the brick size",
            volume: gen("nbody:13x37x21")?,
            tf: "ramp:0.2:1:0.6",
            views: vec![
                cam(32, 30.0, 20.0, ORTHO, 0.5, None)?,
                cam(32, -140.0, -25.0, persp(None, 50.0), 0.5, None)?,
            ],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "degenerate dims 1 x 1 x N",
            volume: gen("shells:1x1x40")?,
            tf: "ramp:0.2:1:0.6",
            views: vec![cam(24, 30.0, 20.0, ORTHO, 0.5, None)?],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "transparent transfer function",
            volume: gen("vessels:40")?,
            tf: "band:0:1:0",
            views: vec![cam(32, 30.0, 20.0, ORTHO, 0.5, None)?],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "opaque transfer function",
            volume: gen("vessels:40")?,
            tf: "band:0:1:0.05",
            views: vec![
                cam(32, 30.0, 20.0, ORTHO, 0.5, None)?,
                cam(32, 30.0, 20.0, ORTHO, 0.5, Some(0.95))?,
            ],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "a single active voxel",
            volume: Volume::new("dot", [40; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(dot))?,
            tf: "band:0.02:1:1",
            views: vec![
                cam(32, 0.0, 0.0, ORTHO, 0.5, None)?,
                cam(32, 45.0, 35.264389682754654, ORTHO, 0.37, None)?,
            ],
            iso: "0.3",
            look: LookSpec::default(),
        },
        HardCase {
            name: "spike narrower than the gap between voxel values",
            volume: Volume::new("halves", [24; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(halves))?,
            tf: "spike:0.5:0.0005",
            views: vec![
                cam(24, 90.0, 0.0, ORTHO, 0.5, None)?,
                cam(24, 80.0, 10.0, ORTHO, 0.25, None)?,
            ],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "steps that do not divide the box",
            volume: gen("nbody:40")?,
            tf: "ramp:0.3:1",
            views: vec![
                cam(32, 17.0, 23.0, ORTHO, 0.3, None)?,
                cam(32, 17.0, 23.0, ORTHO, 0.77, None)?,
                cam(32, 17.0, 23.0, ORTHO, 1.9, None)?,
            ],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "large t (a 4 x 4 x 3000 volume)",
            volume: Volume::new("long", [4, 4, 3000], [1.0; 3], VoxelType::U8, VoxelData::U8(long))?,
            tf: "band:0.5:1:0.01",
            views: vec![
                cam(16, 0.0, 0.0, ORTHO, 0.5, None)?,
                cam(16, 0.3, 0.2, ORTHO, 0.7, None)?,
                cam(16, 180.0, 0.0, persp(Some(1.2), 1.0), 0.5, None)?,
            ],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "a clip plane through the eye",
            volume: gen("shells:40")?,
            tf: "ramp:0.2:1:0.8",
            // The eye at the centre (20, 20, 20), on the plane.
            views: vec![cam(32, 30.0, 10.0, persp(Some(0.0), 90.0), 0.5, None)?],
            iso: "0.5",
            look: LookSpec {
                clip: vec!["1,0.3,0,-26".into()],
                ..LookSpec::default()
            },
        },
        HardCase {
            name: "a clip plane parallel to the rays, on a brick face",
            volume: gen("turbulence:32")?,
            tf: "ramp:0.5:1:0.3",
            views: vec![cam(32, 0.0, 0.0, ORTHO, 0.5, None)?],
            iso: "0.5",
            look: LookSpec {
                clip: vec!["1,0,0,-16".into(), "0,-1,0,24".into()],
                ..LookSpec::default()
            },
        },
        HardCase {
            name: "an oblique clip plane and a crop box cutting bricks",
            volume: gen("vessels:40")?,
            tf: "ramp:0.3:1",
            views: vec![
                cam(32, 30.0, 20.0, ORTHO, 0.5, None)?,
                cam(32, -120.0, 35.0, persp(None, 50.0), 0.5, None)?,
            ],
            iso: "0.4",
            look: LookSpec {
                clip: vec!["0.6,-0.3,0.7,-14.5".into()],
                crop: Some("3.5:37,5:30.25,0:33".into()),
                ..LookSpec::default()
            },
        },
        HardCase {
            name: "a crop box of zero thickness",
            volume: gen("nbody:40")?,
            tf: "ramp:0.3:1",
            views: vec![
                cam(32, 0.0, 0.0, ORTHO, 0.5, None)?,
                cam(32, 30.0, 20.0, ORTHO, 0.5, None)?,
            ],
            iso: "0.5",
            look: LookSpec {
                crop: Some("0:40,0:40,20:20".into()),
                ..LookSpec::default()
            },
        },
        HardCase {
            name: "a clip plane that removes everything",
            volume: gen("nbody:40")?,
            tf: "ramp:0.3:1",
            views: vec![cam(32, 30.0, 20.0, persp(None, 50.0), 0.5, None)?],
            iso: "0.5",
            look: LookSpec {
                clip: vec!["0,1,0,-41".into()],
                ..LookSpec::default()
            },
        },
        HardCase {
            name: "NaN-masked float data (NaN, +inf, -inf voxels)",
            volume: masked("vessels:40")?,
            tf: "ramp:0.3:1",
            views: vec![
                cam(32, 30.0, 20.0, ORTHO, 0.5, None)?,
                cam(32, 0.0, 0.0, persp(None, 50.0), 0.5, None)?,
            ],
            iso: "0.4",
            look: LookSpec::default(),
        },
        HardCase {
            name: "a time step with nothing visible",
            volume: quiet,
            tf: "ramp:0.3:1",
            views: vec![cam(32, 30.0, 20.0, ORTHO, 0.5, None)?],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "a time step whose visible set crossed brick faces",
            volume: moved,
            tf: "ramp:0.3:1",
            views: vec![cam(32, 30.0, 20.0, ORTHO, 0.5, None)?, along_z_through_brick_faces()?],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "two channels, one transparent",
            volume: Volume::join(vec![gen("nbody:40")?, gen("vessels:40")?])?,
            tf: "ramp:0.35:1 | ramp:0:1:0",
            views: vec![cam(32, 30.0, 20.0, ORTHO, 0.5, None)?, along_z_through_brick_faces()?],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "two channels, one dense and one sparse",
            volume: Volume::join(vec![gen("menger:27")?, gen("nbody:27")?])?,
            tf: "ramp:0.5:1:0.2 | ramp:0.35:1",
            views: vec![cam(32, 30.0, 20.0, ORTHO, 0.5, None)?],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "channels of other types and ranges (u8 with float32 NaN-masked)",
            volume: Volume::join(vec![gen("vessels:40")?, masked("nbody:40")?])?,
            tf: "ramp:0.3:1 | ramp:0.35:1",
            views: vec![
                cam(32, 30.0, 20.0, ORTHO, 0.5, None)?,
                cam(32, 0.0, 0.0, persp(None, 50.0), 0.5, None)?,
            ],
            iso: "0.5",
            look: LookSpec::default(),
        },
        HardCase {
            name: "a volume of NaN only",
            volume: Volume::new(
                "all NaN",
                [24, 20, 16],
                [1.0; 3],
                VoxelType::F32,
                VoxelData::F32(vec![f32::NAN; 24 * 20 * 16]),
            )?,
            tf: "ramp:0:1:1",
            views: vec![cam(24, 30.0, 20.0, ORTHO, 0.5, None)?],
            iso: "0.5",
            look: LookSpec::default(),
        },
    ])
}
