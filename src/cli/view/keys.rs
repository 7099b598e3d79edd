//! What the viewer's keys do (`--keys` scripts them): a new TF or
//! structure is rebuilt at once; a look the volume cannot show is skipped;
//! a script whose keys could never show is refused.

use super::controls::{Change, Shape, SHIFT_TAB};
use super::{ViewArgs, Viewer, FRAME_KEY, QUIT_KEYS};
use lacuna::{Error, Result, TransferFunction};

impl Viewer {
    /// Presses the scripted keys up to the next `frame` (`--keys`); a
    /// quitting key (Esc, Q) ends the session there (`self.quit`).
    pub(super) fn press_pending(&mut self) -> Result<()> {
        while let Some(key) = self.pending_keys.pop_front() {
            if key == FRAME_KEY {
                break;
            }
            self.quit |= self.key(&key);
            if let Some(e) = self.key_result.take() {
                return Err(e);
            }
            if self.quit {
                self.pending_keys.clear();
            }
        }
        Ok(())
    }

    /// Applies a key: a new TF or structure is rebuilt now. True to quit.
    pub(super) fn key(&mut self, name: &str) -> bool {
        self.dirty = true;
        let before = (self.controls.presets.clone(), self.controls.preset);
        let look = self.controls.look.clone();
        let (name, shift) = match name {
            SHIFT_TAB => ("Tab", true),
            name => (name, self.modifiers.shift_key()),
        };
        let change = self.controls.key(name, shift);
        if let Some(why) = change.ignored {
            say_err!("note: key {name}: {why}");
        }
        // A look this volume cannot show is skipped: the key is pressed
        // again (the mode key's next mode; a toggle's way back).
        let mut refused = None;
        for _ in 0..8 {
            match self.look_fits() {
                Ok(()) => break,
                Err(e) => refused = refused.or(Some(e)),
            }
            if self.controls.look == look {
                break;
            }
            self.controls.key(name, shift);
        }
        if let Some(e) = refused {
            say_err!("note: look skipped: {e}");
        }
        if self.look_fits().is_err() {
            self.controls.look = look;
        }
        self.key_result = self.apply(change, before).err();
        change.quit
    }

    /// Whether the controls' look can be drawn on this volume: a key that
    /// asks for one it cannot (shading on several channels) is refused in
    /// the viewer, as `render` refuses the flag, not the session ended.
    /// Only that: the frame's other errors surface where it is drawn.
    fn look_fits(&self) -> Result<()> {
        let volume = &self.scene.volume;
        let Ok(desc) = self.controls.desc(volume.dims, volume.spacing, self.filter) else {
            return Ok(());
        };
        if desc.lighting().is_some() && volume.channel_count() > 1 {
            return Err(Error::invalid(
                "look",
                self.controls.look.describe(),
                format!(
                    "shaded and iso frames take one channel, and {} has {}",
                    volume.name,
                    volume.channel_count()
                ),
            ));
        }
        Ok(())
    }

    fn apply(&mut self, change: Change, before: (Vec<Shape>, usize)) -> Result<()> {
        if change.tf {
            // A TF the keys made invalid, or a JSON file that no longer
            // reads, is reported and the current one kept.
            let (read, notes) = self
                .controls
                .read_preset(change.cycled, TransferFunction::parse_channels);
            for note in notes {
                say_err!("note: {note}");
            }
            match read {
                Some(tf) => self.scene.set_tf(tf)?,
                None => (self.controls.presets, self.controls.preset) = before,
            }
        }
        if change.structure && self.scene.accel.name() != self.controls.accel.name() {
            self.scene.set_accel(self.controls.accel);
        } else if change.structure {
            self.scene.set_mode(self.controls.look.mode);
        }
        if change.screenshot {
            self.shots += 1;
        }
        Ok(())
    }
}

impl ViewArgs {
    /// Keys that would never show are refused: those after the last frame
    /// `--frames` draws; with `--frames`, a quitting key where the last
    /// frame is to be written (`--screenshot`); keys after a quitting key;
    /// and an S with no frame drawn between it and a quitting key.
    pub(super) fn check_key_script(&self) -> Result<()> {
        let quits = |k: &String| QUIT_KEYS.iter().any(|q| k.eq_ignore_ascii_case(q));
        let refuse = |message: String| Err(Error::invalid("keys", self.keys.join(","), message));
        if let (Some(_), Some(_), Some(_)) = (self.keys.iter().find(|k| quits(k)), &self.screenshot, self.frames) {
            return refuse(
                "q and Escape end the session before --frames' last frame, so --screenshot would never be written: leave them out and let --frames end the session".into(),
            );
        }
        if let Some(q) = self.keys.iter().position(quits) {
            if q + 1 < self.keys.len() {
                return refuse(format!("the keys after {} are never pressed", self.keys[q]));
            }
            let shot = self.keys[..q].iter().rposition(|k| k.eq_ignore_ascii_case("s"));
            if shot.is_some_and(|s| !self.keys[s..q].iter().any(|k| k == FRAME_KEY)) {
                return refuse(format!(
                    "S asks for the next frame, which {} ends the session before: put `frame` between them",
                    self.keys[q]
                ));
            }
        }
        // Keys after the j-th `frame` are pressed once frame j is drawn; a
        // quitting key shows nothing.
        let last_key = self.keys.iter().rposition(|k| k != FRAME_KEY && !quits(k));
        let frames_before = |i: usize| self.keys[..i].iter().filter(|k| *k == FRAME_KEY).count() as u64;
        if let (Some(i), Some(n)) = (last_key, self.frames) {
            let needed = frames_before(i) + 1;
            if u64::from(n) < needed {
                return refuse(format!(
                    "its last keys show from frame {needed}, but --frames {n} ends the session first: give --frames {needed} or more"
                ));
            }
        }
        Ok(())
    }
}
