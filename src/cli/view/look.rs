//! The look the viewer's keys change: the frame mode (`M`), the iso value
//! (`,` and `.`), gradient shading (`L`), jitter (`X`), and a clip plane
//! that cuts the volume facing the camera (`C` shows it, `PageUp` and
//! `PageDown` move it, `V` turns it to face the current view). Pure state,
//! no GPU; the clip planes and crop box given on the command line stay.

use lacuna::render::{Camera, Clip, FrameBuilder, FrameDesc, Iso, Mode, Orbit, Shading, MAX_CLIP};
use lacuna::Result;

/// The modes `M` cycles through.
const MODES: [&str; 5] = ["composite", "mip", "minip", "average", "iso"];
/// How far `,` and `.` move the iso value.
const ISO_NUDGE: f32 = 0.02;
/// How far one `PageUp` / `PageDown` moves the clip plane, in voxels.
const PLANE_NUDGE: f32 = 2.0;

/// The key names `LookControls::key` acts on.
pub const KEYS: &[&str] = &["m", ",", ".", "l", "x", "c", "v", "PageUp", "PageDown"];

/// The viewer's clip plane: facing the camera of these orbit angles, through
/// the volume's centre moved `offset` voxels away from the eye; it keeps
/// what lies beyond it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewPlane {
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
    pub offset: f32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct LookControls {
    pub mode: Mode,
    /// The iso values `M` returns to (the first one moves with `,` and `.`).
    pub iso: Iso,
    /// The shading `L` switches on (the command line's, else the default).
    pub shading: Shading,
    pub shade: bool,
    pub jitter: bool,
    /// The command line's clip planes and crop box.
    pub clip: Clip,
    pub plane: Option<ViewPlane>,
}

/// What a look key changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LookChange {
    /// The mode or the iso value: the structure is built for it.
    pub rebuild: bool,
    /// Why the key did nothing (a `note:` for the user), if it did not.
    pub ignored: Option<&'static str>,
}

impl LookControls {
    pub fn new(frame: &FrameDesc) -> Self {
        let iso = match frame.mode() {
            Mode::Iso(iso) => *iso,
            _ => Iso::new(&[0.5]).expect("0.5 is a valid iso value"),
        };
        LookControls {
            mode: *frame.mode(),
            iso,
            shading: frame.shading().copied().unwrap_or_default(),
            shade: frame.shading().is_some(),
            jitter: frame.jitter(),
            clip: *frame.clip(),
            plane: None,
        }
    }

    /// Applies `key` with the camera at `orbit`.
    pub fn key(&mut self, key: &str, orbit: &Orbit) -> LookChange {
        let mut change = LookChange::default();
        match key {
            "m" | "M" => {
                let i = MODES.iter().position(|m| *m == self.mode.name()).unwrap_or(0);
                self.mode = match MODES[(i + 1) % MODES.len()] {
                    "iso" => Mode::Iso(self.iso),
                    name => Mode::parse(name, None).unwrap_or_default(),
                };
                change.rebuild = true;
            }
            "," | "." => {
                let d = if key == "," { -ISO_NUDGE } else { ISO_NUDGE };
                let mut values = self.iso.values().to_vec();
                values[0] = ((values[0] + d).clamp(0.0, 1.0) * 1000.0).round() / 1000.0;
                let moved = Iso::new(&values).and_then(|m| match self.iso.color {
                    Some(c) => m.with_color(c),
                    None => Ok(m),
                });
                if let Ok(moved) = moved {
                    self.iso = moved;
                }
                match self.mode {
                    Mode::Iso(_) => {
                        self.mode = Mode::Iso(self.iso);
                        change.rebuild = true;
                    }
                    _ => change.ignored = Some("the iso value moved; it shows once M reaches iso"),
                }
            }
            "l" | "L" => {
                self.shade = !self.shade;
                if matches!(self.mode, Mode::Mip | Mode::MinIp | Mode::Average) {
                    change.ignored =
                        Some("shading lights composite frames (iso surfaces always): it shows once M reaches them");
                }
            }
            "x" | "X" => self.jitter = !self.jitter,
            // The command line's planes may leave no room for another.
            "c" | "C" | "v" | "V" if self.plane.is_none() && self.clip.planes().len() == MAX_CLIP => {
                change.ignored = Some("the command line gives six clip planes already, the most a frame takes")
            }
            "c" | "C" => {
                self.plane = match self.plane {
                    Some(_) => None,
                    None => Some(ViewPlane {
                        azimuth_deg: orbit.azimuth_deg,
                        elevation_deg: orbit.elevation_deg,
                        offset: 0.0,
                    }),
                }
            }
            "v" | "V" => {
                let offset = self.plane.map_or(0.0, |p| p.offset);
                self.plane = Some(ViewPlane {
                    azimuth_deg: orbit.azimuth_deg,
                    elevation_deg: orbit.elevation_deg,
                    offset,
                });
            }
            "PageUp" | "PageDown" => {
                let d = if key == "PageUp" { PLANE_NUDGE } else { -PLANE_NUDGE };
                match &mut self.plane {
                    Some(p) => p.offset += d,
                    None => change.ignored = Some("no clip plane is shown (C shows one)"),
                }
            }
            _ => change.ignored = Some("no key of the viewer's (README, \"Viewer\", lists them)"),
        }
        change
    }

    /// The clip plane `A,B,C,D` (voxel space) of the view plane, for a
    /// volume of `dims` voxels with `spacing`.
    pub fn plane_equation(&self, dims: [u32; 3], spacing: [f32; 3]) -> Result<Option<[f32; 4]>> {
        let Some(p) = self.plane else {
            return Ok(None);
        };
        let facing = Orbit {
            azimuth_deg: p.azimuth_deg,
            elevation_deg: p.elevation_deg,
            ..Orbit::default()
        };
        // An orthographic orbit's rays run along the view direction, in
        // voxel space: the world's direction over the spacing. A plane
        // facing the camera in the world has the world direction for its
        // normal, which in voxel space is the direction times the spacing
        // twice over (relative to the shortest side, which f32 squares
        // at any spacing).
        let dir = Camera::Orbit(facing).rays(dims, spacing, 1, 1)?.eye_or_dir;
        let shortest = spacing.iter().fold(f64::INFINITY, |m, s| m.min(*s as f64));
        let world = std::array::from_fn::<f64, 3, _>(|a| {
            let r = spacing[a] as f64 / shortest;
            dir[a] as f64 * r * r
        });
        let len = world.iter().map(|c| c * c).sum::<f64>().sqrt();
        let n = world.map(|c| (c / len) as f32);
        let centre = dims.map(|d| d as f32 / 2.0);
        let d = -(n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2]) - p.offset;
        Ok(Some([n[0], n[1], n[2], d]))
    }

    /// The look set on `b`: shading only where the mode lights samples
    /// (composite with `L` on; iso always).
    pub fn apply(&self, b: FrameBuilder, dims: [u32; 3], spacing: [f32; 3]) -> Result<FrameBuilder> {
        let lit = match self.mode {
            Mode::Composite => self.shade,
            Mode::Iso(_) => true,
            _ => false,
        };
        let mut clip = self.clip;
        if let Some(plane) = self.plane_equation(dims, spacing)? {
            clip = clip.plane(plane)?;
        }
        Ok(b.mode(self.mode)
            .shading(lit.then_some(self.shading))
            .clip(clip)
            .jitter(self.jitter))
    }

    /// For the title: `mode mip · shaded · jitter · clip plane +4`.
    pub fn describe(&self) -> String {
        let mut parts = vec![match &self.mode {
            Mode::Iso(i) => format!("iso {}", i.values()[0]),
            m => m.name().to_string(),
        }];
        if self.shade && matches!(self.mode, Mode::Composite) {
            parts.push("shaded".into());
        }
        if self.jitter {
            parts.push("jitter".into());
        }
        if let Some(p) = self.plane {
            parts.push(format!("clip plane {:+}", p.offset));
        }
        parts.join(" · ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn look() -> LookControls {
        LookControls::new(&FrameDesc::builder(64, 64).build().unwrap())
    }

    #[test]
    fn m_cycles_the_modes_and_iso_keeps_its_value() {
        let mut l = look();
        let orbit = Orbit::default();
        let mut names = Vec::new();
        for _ in 0..5 {
            assert!(l.key("m", &orbit).rebuild);
            names.push(l.mode.name());
        }
        assert_eq!(names, ["mip", "minip", "average", "iso", "composite"]);
        // The iso value moves in any mode and rebuilds only in iso mode.
        assert!(!l.key(".", &orbit).rebuild);
        for _ in 0..4 {
            l.key("m", &orbit);
        }
        assert!(l.key(",", &orbit).rebuild);
        assert_eq!(l.mode, Mode::Iso(Iso::new(&[0.5]).unwrap()));
        for _ in 0..40 {
            l.key(",", &orbit);
        }
        assert_eq!(l.iso.values(), [0.0], "clamped to the data range");
    }

    #[test]
    fn the_view_plane_faces_the_camera_through_the_centre_and_moves() {
        let mut l = look();
        let dims = [40, 30, 20];
        assert_eq!(l.plane_equation(dims, [1.0; 3]).unwrap(), None);
        assert!(l.key("PageUp", &Orbit::default()).ignored.is_some(), "no plane to move");
        let head_on = Orbit {
            azimuth_deg: 0.0,
            elevation_deg: 0.0,
            ..Orbit::default()
        };
        l.key("c", &head_on);
        // Looking down -z: the plane z = 10 keeps what lies beyond it.
        let [a, b, c, d] = l.plane_equation(dims, [1.0; 3]).unwrap().unwrap();
        assert!(a.abs() < 1e-6 && b.abs() < 1e-6 && (c + 1.0).abs() < 1e-6 && (d - 10.0).abs() < 1e-5);
        l.key("PageUp", &head_on);
        let moved = l.plane_equation(dims, [1.0; 3]).unwrap().unwrap();
        assert!(
            (moved[3] - 8.0).abs() < 1e-5,
            "{moved:?}: 2 voxels further from the eye"
        );
        let side = Orbit {
            azimuth_deg: 90.0,
            ..head_on
        };
        l.key("v", &side);
        let turned = l.plane_equation(dims, [1.0; 3]).unwrap().unwrap();
        assert!((turned[0] + 1.0).abs() < 1e-6, "{turned:?}: now facing +x");
        l.key("c", &side);
        assert_eq!(l.plane, None);
    }

    #[test]
    fn the_view_plane_faces_the_camera_in_the_world_on_uneven_spacing() {
        let mut l = look();
        let orbit = Orbit::default();
        l.key("c", &orbit);
        // With even spacing voxel space is the world's, scaled.
        let [a, b, c, _] = l.plane_equation([40, 24, 16], [1.0; 3]).unwrap().unwrap();
        let spacing = [1.0f32, 1.5, 2.0];
        // A plane n . (voxel * spacing) + d = 0 has the voxel-space normal
        // n * spacing.
        let want = [a * spacing[0], b * spacing[1], c * spacing[2]];
        let len = want.iter().map(|v| v * v).sum::<f32>().sqrt();
        let got = l.plane_equation([40, 24, 16], spacing).unwrap().unwrap();
        for i in 0..3 {
            assert!((got[i] - want[i] / len).abs() < 1e-5, "{got:?} against {want:?}");
        }
        // Through the volume's centre.
        let centre = [20.0, 12.0, 8.0];
        let at: f32 = (0..3).map(|i| got[i] * centre[i]).sum::<f32>() + got[3];
        assert!(at.abs() < 1e-4, "{at}");
    }

    #[test]
    fn shading_applies_where_the_mode_lights_samples() {
        let mut l = look();
        l.key("l", &Orbit::default());
        let desc = |l: &LookControls| {
            l.apply(FrameDesc::builder(8, 8), [8; 3], [1.0; 3])
                .unwrap()
                .build()
                .unwrap()
        };
        assert!(desc(&l).shading().is_some());
        l.key("m", &Orbit::default());
        assert!(desc(&l).shading().is_none(), "mip frames are not lit");
        l.key("x", &Orbit::default());
        assert!(desc(&l).jitter());
        assert_eq!(l.describe(), "mip · jitter");
    }
}
