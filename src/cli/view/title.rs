//! What the viewer's title and its `--frames` summary say.

use super::Viewer;
use lacuna::render::{self, Octants};

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
            "frames {}: {:.1} fps, march {:.3} ms, rebuild {:.3} ms ({}{octants}){}{step}{}",
            self.drawn,
            self.fps,
            self.scene.march_ms(),
            self.scene.rebuild_ms(),
            self.accel_text(),
            if step.is_empty() { "" } else { ", " },
            self.cut_text(),
        )
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

    pub(super) fn title(&self) -> String {
        let scene = &self.scene;
        let accel = self.accel_text();
        let c = &self.controls;
        let step = self.step_text();
        let cut = self.cut_text();
        format!(
            "lacuna view · {}{}{step} · {accel} · {} · {} · {:.1} fps · march {:.2} ms · rebuild {:.2} ms · step {} · ERT {}{cut}",
            scene.volume.name,
            if step.is_empty() { "" } else { " · " },
            scene.tf.spec,
            c.look.describe(),
            self.fps,
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
