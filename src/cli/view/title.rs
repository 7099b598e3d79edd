//! What the viewer's title and its `--frames` summary say.

use super::Viewer;
use lacuna::render::{self, Octants, Projection};

impl Viewer {
    /// "time step K of N" for a series; empty for one volume.
    fn step_text(&self) -> String {
        match self.series.steps() {
            1 => String::new(),
            n => format!(
                "time step {} of {n} (load {:.1} ms, upload {:.1} ms)",
                self.shown,
                self.load_ms,
                self.scene.upload_ms()
            ),
        }
    }

    /// The `--frames` run's last line: what the title showed last.
    pub(super) fn summary(&self) -> String {
        let step = self.step_text();
        // An octant map holds the ray directions of the frames so far.
        let octants = match self.scene.structure.octants() {
            o if o == Octants::ALL => String::new(),
            o => format!(", {} of 8 octants", o.len()),
        };
        format!(
            "frames {}: {}, march {:.3} ms, rebuild {:.3} ms ({}{octants}){}{step}{}",
            self.drawn,
            self.rate_text(),
            self.scene.march_ms(),
            self.scene.rebuild_ms(),
            self.accel_text(),
            if step.is_empty() { "" } else { ", " },
            self.cut_text(),
        )
    }

    /// The frame rate over back-to-back frames (`--frames`, a playing
    /// series, scripted keys), else the last frame's wall time: the window
    /// is not redrawn while nothing changes, so idle time is no frame's.
    fn rate_text(&self) -> String {
        match self.fps {
            0.0 => format!("frame {:.1} ms", self.frame_ms),
            fps => format!("{fps:.1} fps"),
        }
    }

    /// What a frame the device's loop cap cut short adds to the title
    /// (`Renderer::check_whole`): that it is not the exact frame.
    fn cut_text(&self) -> String {
        match self.scene.cut_groups {
            0 => String::new(),
            n => format!(" · NOT EXACT: the device's loop cap cut {n} SIMD group(s) short, take a coarser step"),
        }
    }

    /// The structure, and what marched it where another kernel did
    /// (`auto -> distance-octant (cell 4)`, `kd-cpu -> naive`).
    fn accel_text(&self) -> String {
        let scene = &self.scene;
        match scene.structure.marched_as_reason() {
            Some(m) => format!("{} -> {}", scene.accel, m.label),
            None => scene.accel.to_string(),
        }
    }

    /// The orbit as `render` takes it, and the zoom and pan where they
    /// moved (`render` has neither): `camera 30.0,20.0 perspective 40 ·
    /// zoom 1.50x · pan 0.10,0.00`.
    fn camera_text(&self) -> String {
        let c = &self.controls;
        let projection = match c.orbit.projection {
            Projection::Orthographic => "orthographic".to_string(),
            Projection::Perspective { fov_deg, .. } => format!("perspective {fov_deg}"),
        };
        let zoom = match c.zoom {
            1.0 => String::new(),
            z => format!(" · zoom {z:.2}x"),
        };
        // In viewport heights, as `Controls::pan` keeps it.
        let pan = match c.pan == glam::DVec2::ZERO {
            true => String::new(),
            false => format!(" · pan {:.2},{:.2}", c.pan.x, c.pan.y),
        };
        format!(
            "camera {:.1},{:.1} {projection}{zoom}{pan}",
            c.orbit.azimuth_deg, c.orbit.elevation_deg
        )
    }

    pub(super) fn title(&self) -> String {
        let scene = &self.scene;
        let accel = self.accel_text();
        let c = &self.controls;
        let step = self.step_text();
        let cut = self.cut_text();
        format!(
            "lacuna view · {}{}{step} · {accel} · {} · {} · {} · frame {:.1} ms · march {:.2} ms · rebuild {:.2} ms · step {} · ERT {}{cut}",
            scene.volume.name,
            if step.is_empty() { "" } else { " · " },
            scene.tf.spec,
            c.look.describe(),
            self.camera_text(),
            self.frame_ms,
            scene.march_ms(),
            scene.rebuild_ms(),
            c.step,
            // Early termination ends composite rays only.
            match c.look.mode {
                render::Mode::Composite => c.ert.map_or("off".to_string(), |e| e.to_string()),
                _ => "off".to_string(),
            },
        )
    }
}
