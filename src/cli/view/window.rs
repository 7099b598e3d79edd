//! The window's part: which keys are keys, the frame's size for a window
//! past the device's limits, winit's errors without build paths, and
//! Ctrl-C as an event of the window's loop.

use winit::event_loop::EventLoop;
use winit::keyboard::Key;

/// `size`, or where it does not `fits`, the largest of the same shape that
/// does (to within 0.1 % of its sides: a bisection of the scale).
pub(super) fn fit(size: (u32, u32), fits: impl Fn((u32, u32)) -> bool) -> (u32, u32) {
    if fits(size) {
        return size;
    }
    let scaled = |s: f64| {
        let side = |n: u32| ((n as f64 * s).floor() as u32).max(1);
        (side(size.0), side(size.1))
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..20 {
        let mid = (lo + hi) / 2.0;
        match fits(scaled(mid)) {
            true => lo = mid,
            false => hi = mid,
        }
    }
    scaled(lo)
}

/// Shift, Control, Alt and the like, and the lock keys: pressed on their
/// own they ask for nothing.
pub(super) fn is_modifier(key: &Key) -> bool {
    use winit::keyboard::NamedKey::*;
    matches!(
        key,
        Key::Named(
            Shift
                | Control
                | Alt
                | AltGraph
                | Super
                | Meta
                | Hyper
                | Fn
                | FnLock
                | CapsLock
                | NumLock
                | ScrollLock
                | Symbol
                | SymbolLock
        )
    )
}

/// A windowing error without where in winit's sources it was raised: winit
/// writes `os error at /path/to/registry/winit-x/src/...rs:765: reason`,
/// and a user needs the reason, not a build path.
pub(super) fn without_source_location(message: &str) -> String {
    let Some(at) = message.find("os error at ") else {
        return message.to_string();
    };
    let rest = &message[at + "os error at ".len()..];
    // The location ends at the first ".rs:LINE: ".
    let reason = rest.find(".rs:").and_then(|i| {
        let after = &rest[i + 4..];
        let digits = after.chars().take_while(char::is_ascii_digit).count();
        after[digits..].strip_prefix(": ").filter(|_| digits > 0)
    });
    match reason {
        Some(reason) => format!("{}{}", &message[..at], reason),
        None => message.to_string(),
    }
}

/// Ctrl-C or SIGTERM arrived.
pub(super) struct Signalled;

/// Ctrl-C and SIGTERM end the session as Q does: lacuna's and the window's
/// objects are released, validation's verdict stands and the title's
/// figures are printed, rather than the process dying mid-frame. A second
/// one ends the process at once (exit 130), for a session stuck in a frame.
pub(super) fn end_on_signals(event_loop: &EventLoop<Signalled>) {
    let proxy = event_loop.create_proxy();
    let asked = std::sync::atomic::AtomicBool::new(false);
    if let Err(e) = ctrlc::set_handler(move || {
        if asked.swap(true, std::sync::atomic::Ordering::SeqCst) {
            std::process::exit(130);
        }
        let _ = proxy.send_event(Signalled);
    }) {
        say_err!("note: Ctrl-C ends the process, not the session: {e}");
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn window_errors_name_no_build_path() {
        let winit = "os error at /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/winit-0.30.13/src/platform_impl/linux/mod.rs:765: neither WAYLAND_DISPLAY nor WAYLAND_SOCKET nor DISPLAY is set.";
        assert_eq!(
            super::without_source_location(winit),
            "neither WAYLAND_DISPLAY nor WAYLAND_SOCKET nor DISPLAY is set."
        );
        assert_eq!(super::without_source_location("no display"), "no display");
    }

    #[test]
    fn a_window_past_the_device_renders_the_largest_frame_of_its_shape_that_fits() {
        // lavapipe's 128 MiB storage range at 16 bytes a pixel.
        let fits = |(w, h): (u32, u32)| w as u64 * h as u64 * 16 <= 1 << 27;
        assert_eq!(super::fit((256, 256), fits), (256, 256));
        // The largest square that fits is 2896x2896.
        assert_eq!(super::fit((3000, 3000), fits), (2896, 2896));
        let (w, h) = super::fit((9000, 1500), fits);
        assert!(fits((w, h)) && w / h == 6 && !fits((w + 6, h + 1)), "{w}x{h}");
    }

    #[test]
    fn modifier_keys_alone_are_no_keys() {
        use winit::keyboard::{Key, NamedKey};
        assert!(super::is_modifier(&Key::Named(NamedKey::Shift)));
        assert!(super::is_modifier(&Key::Named(NamedKey::CapsLock)));
        assert!(!super::is_modifier(&Key::Named(NamedKey::Tab)));
        assert!(!super::is_modifier(&Key::Character("t".into())));
    }
}
