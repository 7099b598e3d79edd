//! What the user changes in the viewer, and how input changes it: orbit,
//! zoom and pan (host math through glam), the transfer function's shape,
//! the structure, early ray termination, the step, and the look
//! (`look.rs`). Pure state, no GPU.

use super::look::{self, LookControls};
pub use super::tf_shape::Shape;
use super::tf_shape::TF_NUDGE;
use glam::{DVec2, Vec3};
use lacuna::accel::{Accel, TABLE};
use lacuna::render::{Camera, Filter, FrameDesc, Orbit, Projection};
use lacuna::Result;

/// Steps the `[` and `]` keys move between, in voxels.
const STEPS: [f32; 6] = [0.125, 0.25, 0.5, 1.0, 2.0, 4.0];
/// The ERT threshold the `E` key switches on.
const ERT: f32 = 0.99;

/// The key names `Controls::key` acts on (either case for letters), the
/// look's (`look::KEYS`) besides.
const OWN_KEYS: &[&str] = &[
    "ArrowLeft",
    "ArrowRight",
    "ArrowUp",
    "ArrowDown",
    "t",
    "j",
    "Tab",
    "e",
    "[",
    "]",
    "p",
    "r",
    "s",
    "q",
    "Escape",
    "Space",
    "<",
    ">",
];

/// The `--keys` name of Shift+Tab (the previous structure).
pub const SHIFT_TAB: &str = "Shift+Tab";

/// Every key name `Controls::key` acts on.
pub fn keys() -> Vec<&'static str> {
    OWN_KEYS.iter().chain(look::KEYS).copied().collect()
}

/// A `--keys` name as the window names the key: `Comma` is ',' (the list's
/// own separator).
pub fn script_key(name: &str) -> std::result::Result<String, std::convert::Infallible> {
    Ok(match name {
        "Comma" => ",".to_string(),
        other => other.to_string(),
    })
}

/// Every key name as `--keys` takes it, listed for an error.
pub fn script_names() -> String {
    let mut names: Vec<&str> = keys().into_iter().map(|k| if k == "," { "Comma" } else { k }).collect();
    names.push(SHIFT_TAB);
    names.join(", ")
}

/// Whether `Controls::key` acts on `name`.
pub fn known_key(name: &str) -> bool {
    name == SHIFT_TAB
        || keys()
            .iter()
            .any(|k| *k == name || (k.len() == 1 && k.eq_ignore_ascii_case(name)))
}

/// What an input changed, so the viewer redoes only that.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Change {
    /// The transfer function: re-upload it and rebuild the structure.
    pub tf: bool,
    /// The structure, or the mode it is built for: compute its ranges and
    /// build it.
    pub structure: bool,
    /// A screenshot was asked for.
    pub screenshot: bool,
    /// The time step changed: load it, upload it, rebuild.
    pub time: bool,
    /// T cycled the presets: one that does not read (a JSON file gone
    /// since) is passed over, not returned to.
    pub cycled: bool,
    pub quit: bool,
    /// Why the key changed nothing the frame shows (a `note:`), if so.
    pub ignored: Option<&'static str>,
}

/// The viewer's state.
pub struct Controls {
    pub orbit: Orbit,
    pub size: (u32, u32),
    pub step: f32,
    pub ert: Option<f32>,
    /// Image-plane zoom (> 1 magnifies) and pan (in viewport heights) about the
    /// orbit camera's own framing.
    pub zoom: f64,
    pub pan: DVec2,
    /// The orbit to reset to.
    initial: Orbit,
    /// The projection the `P` key switches to (and back from).
    other_projection: Projection,
    /// Transfer-function presets; `T` cycles them, the arrows reshape the current one.
    pub presets: Vec<Shape>,
    pub preset: usize,
    /// A ParaView JSON file the `J` key loads (read again on every press).
    pub json: Option<String>,
    pub accel: Accel,
    pub look: LookControls,
    /// The time step shown, of `steps` (1: one volume).
    pub time: u32,
    pub steps: u32,
    /// Space plays the series: a new step every frame.
    pub playing: bool,
}

impl Controls {
    /// The viewer's state starting at `frame` (an orbit camera; another
    /// camera starts at the default orbit).
    pub fn new(frame: &FrameDesc, tf_spec: &str, accel: Accel, json: Option<String>) -> Self {
        let mut presets = vec![Shape::parse(tf_spec)];
        for spec in ["ramp:0.3:1", "band:0.4:0.6:0.5", "spike:0.5:0.05"] {
            if presets[0].spec() != spec {
                presets.push(Shape::parse(spec));
            }
        }
        let orbit = match frame.camera() {
            Camera::Orbit(o) => *o,
            _ => Orbit::default(),
        };
        // P switches between orthographic and perspective: 40 degrees when
        // started orthographic, else back to orthographic.
        let other_projection = match orbit.projection {
            Projection::Orthographic => Projection::Perspective {
                fov_deg: 40.0,
                distance: None,
            },
            Projection::Perspective { .. } => Projection::Orthographic,
        };
        Controls {
            initial: orbit,
            other_projection,
            orbit,
            size: frame.size(),
            step: frame.step(),
            ert: frame.ert(),
            zoom: 1.0,
            pan: DVec2::ZERO,
            presets,
            preset: 0,
            json,
            accel,
            look: LookControls::new(frame),
            time: 0,
            steps: 1,
            playing: false,
        }
    }

    /// Moves `by` steps through the series, wrapping around.
    pub fn step_time(&mut self, by: i64) -> bool {
        let n = self.steps.max(1) as i64;
        let next = (self.time as i64 + by).rem_euclid(n) as u32;
        let moved = next != self.time;
        self.time = next;
        moved
    }

    /// The current transfer function's spec.
    pub fn tf_spec(&self) -> String {
        self.presets[self.preset].spec()
    }

    /// The current preset, read by `read`; None (and why, in the notes)
    /// where it does not read, as a JSON file gone since. Where T cycled
    /// to it (`cycled`), such a preset is passed over to the next that
    /// reads, so T cannot stick on it.
    pub fn read_preset<T>(&mut self, cycled: bool, read: impl Fn(&str) -> Result<T>) -> (Option<T>, Vec<String>) {
        let n = self.presets.len();
        let mut notes = Vec::new();
        for _ in 0..if cycled { n } else { 1 } {
            match read(&self.tf_spec()) {
                Ok(tf) => return (Some(tf), notes),
                Err(e) if cycled => {
                    notes.push(format!("transfer function {} skipped: {e}", self.tf_spec()));
                    self.preset = (self.preset + 1) % n;
                }
                Err(e) => notes.push(format!("transfer function not changed: {e}")),
            }
        }
        (None, notes)
    }

    /// Orbits by a mouse drag of `(dx, dy)` pixels.
    pub fn orbit(&mut self, dx: f64, dy: f64) {
        let o = &mut self.orbit;
        o.azimuth_deg = (o.azimuth_deg - dx * 0.4).rem_euclid(360.0);
        o.elevation_deg = (o.elevation_deg + dy * 0.4).clamp(-89.0, 89.0);
    }

    /// Pans by a mouse drag of `(dx, dy)` pixels.
    pub fn drag_pan(&mut self, dx: f64, dy: f64) {
        let h = self.size.1.max(1) as f64;
        self.pan += DVec2::new(-dx, -dy) / (h * self.zoom);
    }

    /// Zooms by `lines` mouse-wheel notches (positive: closer).
    pub fn scroll(&mut self, lines: f64) {
        self.zoom = (self.zoom * 1.1f64.powf(lines)).clamp(0.05, 200.0);
    }

    /// Applies a key (by its name as winit gives it: "ArrowLeft", "t", ...).
    pub fn key(&mut self, key: &str, shift: bool) -> Change {
        let mut change = Change::default();
        match key {
            "ArrowLeft" | "ArrowRight" => {
                let d = if key == "ArrowLeft" { -TF_NUDGE } else { TF_NUDGE };
                self.presets[self.preset].shift(d);
                change.tf = self.reshape_note(&mut change);
            }
            "ArrowUp" | "ArrowDown" => {
                let d = if key == "ArrowUp" { TF_NUDGE } else { -TF_NUDGE };
                self.presets[self.preset].widen(d);
                change.tf = self.reshape_note(&mut change);
            }
            "t" | "T" => {
                self.preset = (self.preset + 1) % self.presets.len();
                change.tf = true;
                change.cycled = true;
            }
            "j" | "J" => {
                if let Some(path) = &self.json {
                    let shape = Shape::Fixed(path.clone());
                    match self.presets.iter().position(|p| *p == shape) {
                        Some(i) => self.preset = i,
                        None => {
                            self.presets.push(shape);
                            self.preset = self.presets.len() - 1;
                        }
                    }
                    change.tf = true;
                } else {
                    change.ignored = Some("no ParaView JSON file was given (--json)");
                }
            }
            "Tab" => {
                let i = TABLE.iter().position(|a| a.name() == self.accel.name()).unwrap_or(0);
                let n = TABLE.len();
                self.accel = TABLE[if shift { (i + n - 1) % n } else { (i + 1) % n }];
                change.structure = true;
            }
            "e" | "E" => {
                self.ert = match self.ert {
                    Some(_) => None,
                    None => Some(ERT),
                };
                if !matches!(self.look.mode, lacuna::render::Mode::Composite) {
                    change.ignored =
                        Some("early termination ends composite rays only: it shows once M returns to composite");
                }
            }
            // The next listed step finer or coarser than this one, which
            // need not be listed (`--step`); none past the list's ends.
            "[" => match STEPS.iter().rev().find(|s| **s < self.step) {
                Some(finer) => self.step = *finer,
                None => change.ignored = Some("the step is as fine as the keys make it"),
            },
            "]" => match STEPS.iter().find(|s| **s > self.step) {
                Some(coarser) => self.step = *coarser,
                None => change.ignored = Some("the step is as coarse as the keys make it"),
            },
            "p" | "P" => {
                std::mem::swap(&mut self.other_projection, &mut self.orbit.projection);
            }
            "r" | "R" => {
                let start = self.initial;
                self.orbit.azimuth_deg = start.azimuth_deg;
                self.orbit.elevation_deg = start.elevation_deg;
                self.zoom = 1.0;
                self.pan = DVec2::ZERO;
            }
            "s" | "S" => change.screenshot = true,
            "Space" => {
                self.playing = !self.playing && self.steps > 1;
                if self.steps <= 1 {
                    change.ignored = Some("one volume: no time steps to play");
                }
            }
            // In a series `,` and `.` step through time; `<` and `>` (and,
            // in one volume, `,` and `.`) move the iso value.
            "," | "." if self.steps > 1 => change.time = self.step_time(if key == "," { -1 } else { 1 }),
            "<" | ">" => {
                let nudge = if key == "<" { "," } else { "." };
                let look = self.look.key(nudge, &self.orbit);
                change.structure = look.rebuild;
                change.ignored = look.ignored;
            }
            "Escape" | "q" | "Q" => change.quit = true,
            _ => {
                let look = self.look.key(key, &self.orbit);
                change.structure = look.rebuild;
                change.ignored = look.ignored;
            }
        }
        change
    }

    /// Whether the arrows' reshaping changed the TF; else why not, in `change`.
    fn reshape_note(&self, change: &mut Change) -> bool {
        let reshapes = self.presets[self.preset].reshapes();
        if !reshapes {
            change.ignored =
                Some("the arrows reshape a ramp, band or spike, not this transfer function (T cycles to one)");
        }
        reshapes
    }

    /// The frame for a volume of `dims` voxels with `spacing`: `render`'s
    /// orbit camera for this state, then zoom and pan applied to its pixel
    /// plane (about the plane's centre), so an untouched view is `render`'s
    /// exactly.
    pub fn desc(&self, dims: [u32; 3], spacing: [f32; 3], filter: Filter) -> Result<FrameDesc> {
        let (w, h) = self.size;
        let orbit = Camera::Orbit(self.orbit);
        // Early termination ends composite rays only.
        let ert = self
            .ert
            .filter(|_| matches!(self.look.mode, lacuna::render::Mode::Composite));
        let frame = FrameDesc::builder(w, h)
            .camera(orbit)
            .step(self.step)
            .ert(ert)
            .filter(filter);
        let frame = self.look.apply(frame, dims, spacing)?;
        if self.zoom == 1.0 && self.pan == DVec2::ZERO {
            return frame.build();
        }
        let mut rays = orbit.rays(dims, spacing, w, h)?;
        let (w, h) = (w as f32, h as f32);
        let du = Vec3::from(rays.du);
        let dv = Vec3::from(rays.dv);
        let centre = Vec3::from(rays.base) + du * (w / 2.0) + dv * (h / 2.0);
        let scale = (1.0 / self.zoom) as f32;
        let pan = self.pan.as_vec2() * h;
        let centre: Vec3 = centre + du * pan.x + dv * pan.y;
        let (du, dv) = (du * scale, dv * scale);
        let base = centre - du * (w / 2.0) - dv * (h / 2.0);
        rays.base = base.to_array();
        rays.du = du.to_array();
        rays.dv = dv.to_array();
        frame.camera(Camera::Rays(rays)).build()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn controls(spec: &str) -> Controls {
        let frame = FrameDesc::builder(1024, 1024).build().unwrap();
        Controls::new(&frame, spec, Accel::naive(), Some("cool.json".into()))
    }

    /// What a control changes: TF, structure, camera, step, ERT, zoom,
    /// time step, play.
    #[allow(clippy::type_complexity)]
    fn state(c: &Controls) -> (String, &'static str, Orbit, f32, Option<f32>, f64, u32, bool) {
        (
            c.tf_spec(),
            c.accel.name(),
            c.orbit,
            c.step,
            c.ert,
            c.zoom,
            c.time,
            c.playing,
        )
    }

    #[test]
    fn comma_and_period_step_a_series_and_nudge_the_iso_value_of_one_volume() {
        let mut one = controls("ramp:0.3:1");
        let iso = one.look.iso.values()[0];
        // Outside iso mode the value moves unseen, and the key says so.
        let nudged = one.key(",", false);
        assert!(!nudged.time && nudged.ignored.is_some_and(|w| w.contains("once M reaches iso")));
        assert!(one.look.iso.values()[0] < iso);
        let play = one.key("Space", false);
        assert!(!one.playing, "one volume does not play");
        assert_eq!(play.ignored, Some("one volume: no time steps to play"));
        let lit = one.key("m", false);
        assert!(lit.ignored.is_none());
        assert!(one
            .key("l", false)
            .ignored
            .is_some_and(|w| w.starts_with("shading lights composite")));
        let mut series = controls("ramp:0.3:1");
        series.steps = 3;
        assert!(series.key(",", false).time);
        assert_eq!(series.time, 2, "wraps to the last step");
        assert!(series.key(".", false).time);
        assert_eq!((series.time, series.look.iso.values()[0]), (0, iso));
        series.key(">", false);
        assert!(series.look.iso.values()[0] > iso);
        series.key("Space", false);
        assert!(series.playing);
    }

    #[test]
    fn p_switches_projection_whichever_it_started_with() {
        let mut ortho = controls("ramp:0.3:1");
        ortho.key("p", false);
        assert!(matches!(ortho.orbit.projection, Projection::Perspective { fov_deg, .. } if fov_deg == 40.0));
        ortho.key("p", false);
        assert_eq!(ortho.orbit.projection, Projection::Orthographic);
        let perspective = Projection::Perspective {
            fov_deg: 25.0,
            distance: Some(3.0),
        };
        let frame = FrameDesc::builder(64, 64)
            .orbit(0.0, 20.0, perspective)
            .build()
            .unwrap();
        let mut p = Controls::new(&frame, "ramp:0.3:1", Accel::naive(), None);
        p.key("p", false);
        assert_eq!(p.orbit.projection, Projection::Orthographic);
        p.key("p", false);
        assert_eq!(p.orbit.projection, perspective, "back to --perspective's own");
    }

    #[test]
    fn arrows_move_and_widen_a_window_and_leave_json_alone() {
        let mut c = controls("ramp:0.3:1");
        assert!(c.key("ArrowRight", false).tf);
        assert_eq!(c.tf_spec(), "ramp:0.32:1.02");
        assert!(c.key("ArrowDown", false).tf);
        assert_eq!(c.tf_spec(), "ramp:0.34:1");
        let mut s = controls("spike:0.5:0.05:0.8");
        s.key("ArrowLeft", false);
        s.key("ArrowUp", false);
        assert_eq!(s.tf_spec(), "spike:0.48:0.07:0.8");
        assert!(c.key("j", false).tf);
        assert_eq!(c.tf_spec(), "cool.json");
        assert!(!c.key("ArrowLeft", false).tf, "a JSON TF has no window to move");
        assert_eq!(c.tf_spec(), "cool.json");
    }

    #[test]
    fn every_known_key_does_something_and_others_are_unknown() {
        for key in keys() {
            let mut c = controls("ramp:0.3:1");
            c.zoom = 2.0;
            // A series, for the time keys.
            c.steps = 4;
            // The plane keys move a plane that is shown.
            if key.starts_with("Page") {
                c.key("c", false);
            }
            let before = (state(&c), c.look.clone());
            let change = c.key(key, false);
            let acted = change != Change::default() || (state(&c), c.look.clone()) != before;
            assert!(acted, "{key} did nothing");
            assert!(known_key(key) && (key.len() > 1 || known_key(&key.to_uppercase())));
        }
        assert!(!known_key("z") && !known_key("Arrowleft") && !known_key(""));
        // `--keys` names ',' as Comma: the name maps to the key, and the
        // error's list shows the name.
        assert_eq!(script_key("Comma"), Ok(",".to_string()));
        assert!(script_names().contains(", Comma, ") && !script_names().contains(", , "));
    }

    #[test]
    fn presets_structures_step_and_ert_cycle() {
        let mut c = controls("band:0.4:0.6:0.5");
        let specs: Vec<String> = (0..4).map(|_| (c.key("t", false), c.tf_spec()).1).collect();
        assert_eq!(
            specs,
            ["ramp:0.3:1", "spike:0.5:0.05", "band:0.4:0.6:0.5", "ramp:0.3:1"]
        );
        assert!(c.key("Tab", false).structure);
        assert_eq!(c.accel.name(), TABLE[1].name());
        c.key("Tab", true);
        c.key("Tab", true);
        assert_eq!(c.accel.name(), TABLE[TABLE.len() - 1].name());
        c.key("]", false);
        assert_eq!(c.step, 1.0);
        for _ in 0..9 {
            c.key("[", false);
        }
        assert_eq!(c.step, 0.125);
        c.key("e", false);
        assert_eq!(c.ert, Some(ERT));
        c.key("e", false);
        assert_eq!(c.ert, None);
    }

    #[test]
    fn t_passes_over_a_preset_that_no_longer_reads_and_j_does_not() {
        let mut c = controls("band:0.4:0.6:0.5");
        c.json = Some("gone.json".into());
        c.key("j", false);
        let gone = c.preset;
        // The file went after J loaded it: it no longer reads.
        let read = |spec: &str| match spec {
            "gone.json" => Err(lacuna::Error::invalid("transfer function", spec, "no such file")),
            _ => Ok(spec.to_string()),
        };
        let (tf, notes) = c.read_preset(false, read);
        assert_eq!((tf, notes.len(), c.preset), (None, 1, gone));
        // T from the preset before it lands on it, and goes on past it.
        c.preset = gone - 1;
        let change = c.key("t", false);
        assert_eq!(c.preset, gone);
        let (tf, notes) = c.read_preset(change.cycled, read);
        assert_eq!(tf.as_deref(), Some("band:0.4:0.6:0.5"), "{notes:?}");
        assert!(notes[0].starts_with("transfer function gone.json skipped"), "{notes:?}");
    }

    #[test]
    fn step_keys_go_to_the_next_listed_step_from_any_step() {
        // (start, key, step after, whether the key did anything)
        for (start, key, after, acted) in [
            (8.0, "[", 4.0, true),
            (8.0, "]", 8.0, false),
            (0.05, "]", 0.125, true),
            (0.05, "[", 0.05, false),
            (0.3, "]", 0.5, true),
            (0.3, "[", 0.25, true),
            (0.5, "]", 1.0, true),
            (0.125, "[", 0.125, false),
            (4.0, "]", 4.0, false),
        ] {
            let mut c = controls("ramp:0.3:1");
            c.step = start;
            let change = c.key(key, false);
            assert_eq!((c.step, change.ignored.is_none()), (after, acted), "{start} {key}");
        }
    }

    #[test]
    fn arrows_reshape_every_channels_window_and_say_when_they_cannot() {
        let mut c = controls("ramp:0.3:1|spike:0.5:0.05:0.8");
        assert!(c.key("ArrowRight", false).tf);
        assert_eq!(c.tf_spec(), "ramp:0.32:1.02|spike:0.52:0.05:0.8");
        assert!(c.key("ArrowUp", false).tf);
        assert_eq!(c.tf_spec(), "ramp:0.3:1.04|spike:0.52:0.07:0.8");
        let mut json = controls("cool.json");
        let change = json.key("ArrowLeft", false);
        assert!(!change.tf && change.ignored.is_some());
        let mut none = Controls::new(
            &FrameDesc::builder(8, 8).build().unwrap(),
            "ramp:0.3:1",
            Accel::naive(),
            None,
        );
        assert!(none.key("j", false).ignored.is_some(), "no --json");
        none.key("m", false);
        let ert = none.key("e", false);
        assert_eq!(none.ert, Some(ERT), "kept for composite");
        assert!(ert.ignored.is_some(), "mip frames do not terminate early");
    }

    #[test]
    fn an_untouched_view_is_renders_camera_and_zoom_pan_move_the_pixel_plane() {
        let mut c = controls("ramp:0.3:1");
        let (dims, spacing, norm) = ([40, 30, 20], [1.0, 1.0, 2.0], [1.0, 0.0]);
        let params = |c: &Controls| {
            c.desc(dims, spacing, Filter::Manual)
                .unwrap()
                .params_for(dims, spacing, norm)
                .unwrap()
        };
        let exact = FrameDesc::builder(1024, 1024)
            .build()
            .unwrap()
            .params_for(dims, spacing, norm)
            .unwrap();
        assert_eq!(params(&c), exact);
        c.scroll(1.0);
        let zoomed = params(&c);
        let du = |p: &lacuna::render::RenderParams| Vec3::from(p.du);
        assert!((du(&zoomed) * 1.1 - du(&exact)).length() < 1e-5);
        // Zoom keeps the plane's centre; a pan moves it along the plane.
        let centre = |p: &lacuna::render::RenderParams| Vec3::from(p.base) + du(p) * 512.0 + Vec3::from(p.dv) * 512.0;
        assert!((centre(&zoomed) - centre(&exact)).length() < 1e-3);
        c.drag_pan(10.0, 0.0);
        let panned = params(&c);
        let moved = centre(&panned) - centre(&zoomed);
        assert!((moved + du(&zoomed) * 10.0).length() < 1e-3, "{moved}");
        c.key("r", false);
        assert_eq!(params(&c), exact);
    }
}
