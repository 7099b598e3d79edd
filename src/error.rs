//! The one error type. Every variant renders as a single line that names what
//! is wrong (a path, a dimension, a value, a device limit).

use std::path::PathBuf;

/// Result alias used across the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Non-exhaustive: a new kind of failure is not a breaking change, so a
/// `match` outside lacuna needs a catch-all arm.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A file exists but its contents are not what its format requires.
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
    /// A command-line or API value is malformed or out of range.
    #[error("invalid {what} '{value}': {message}")]
    Invalid {
        what: &'static str,
        value: String,
        message: String,
    },
    /// The request exceeds a limit of the Vulkan device.
    #[error("{what} exceeds the device limit {limit} = {max} on {device}")]
    DeviceLimit {
        what: String,
        limit: &'static str,
        max: u64,
        device: String,
    },
    /// No usable Vulkan driver or device.
    #[error("{0}")]
    NoDevice(String),
    /// A Vulkan call failed.
    #[error("Vulkan error in {call}: {result}")]
    Vulkan {
        call: &'static str,
        result: ash::vk::Result,
    },
    /// The Rust side of a kernel does not match the shader's reflected
    /// interface (a programming error, reported instead of aborting).
    #[error("shader interface mismatch: {0}")]
    Interface(String),
    /// A structure cannot do what was asked (e.g. record a host-driven build).
    #[error("{0}")]
    Unsupported(String),
    /// An input asks for more host memory than is available.
    #[error("{what} needs {bytes} bytes of host memory, over the {available} bytes available (MemAvailable)")]
    HostMemory {
        what: String,
        bytes: String,
        available: u64,
    },
    /// The GPU was lost (driver reset, watchdog) or ran out of memory.
    #[error("{0}")]
    Device(String),
    /// A step several processes take together (MPI ranks) failed in
    /// another process, which reports why.
    #[error("{0} failed in another process")]
    Elsewhere(String),
    /// GPU memory allocation failed.
    #[error("GPU memory allocation for {what} failed: {message}")]
    Memory { what: String, message: String },
    /// A frame's march ran into the device's cap on a shader's loop passes
    /// (`DeviceInfo::loop_pass_limit`), so some rays may have stopped early.
    #[error("the {structure} march ran into {device}'s cap of {limit} loop passes in {groups} SIMD group(s), so their rays may have stopped early and the frame may not be the exact one: {advice}")]
    LoopCap {
        structure: String,
        device: String,
        limit: u64,
        groups: u32,
        /// What to do: a coarser step, or (for a structure) naive marching,
        /// whose march was checked to fit.
        advice: &'static str,
    },
}

impl Error {
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }

    pub fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Format {
            path: path.into(),
            message: clipped(one_line(message.into()), MESSAGE),
        }
    }

    /// Whether the device is too small for what was asked (a limit, or
    /// its memory): the same request may fit a smaller volume or device.
    pub fn is_device_too_small(&self) -> bool {
        matches!(self, Error::DeviceLimit { .. } | Error::Memory { .. })
    }

    pub fn invalid(what: &'static str, value: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Invalid {
            what,
            value: clipped(one_line(value.into()), ECHOED_INPUT),
            message: clipped(one_line(message.into()), MESSAGE),
        }
    }
}

/// A number as a message or a report writes it: as `Display` does (the
/// shortest text that reads back), in exponent form where that would run
/// to many digits (1e300, 1.5e-30).
/// An f32 prints as f32 (its shortest text), not widened.
pub fn number<T: Copy + Into<f64> + std::fmt::Display + std::fmt::LowerExp>(v: T) -> String {
    let w: f64 = v.into();
    match w != 0.0 && w.is_finite() && !(1e-6..1e15).contains(&w.abs()) {
        true => format!("{v:e}"),
        false => format!("{v}"),
    }
}

/// The most characters of input an error echoes, and of a whole message:
/// a 100 MB header line is named, not printed.
const ECHOED_INPUT: usize = 200;
const MESSAGE: usize = 2000;

/// `text` cut to its first `max` characters, saying how long it was.
fn clipped(text: String, max: usize) -> String {
    match text.char_indices().nth(max) {
        None => text,
        Some((end, _)) => format!("{}... ({} bytes in all)", &text[..end], text.len()),
    }
}

/// Input echoed in a message stays on its line: control characters (a
/// newline in a spec, a header or a file name) are escaped.
pub fn one_line(text: String) -> String {
    if !text.contains(char::is_control) {
        return text;
    }
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// Attaches the failing Vulkan entry point to an `ash` result.
pub(crate) trait VkContext<T> {
    fn vk(self, call: &'static str) -> Result<T>;
}

impl<T> VkContext<T> for std::result::Result<T, ash::vk::Result> {
    fn vk(self, call: &'static str) -> Result<T> {
        use ash::vk::Result as R;
        self.map_err(|result| match result {
            R::ERROR_DEVICE_LOST => Error::Device(format!(
                "the GPU device was lost in {call} (driver reset or watchdog; nothing was written)"
            )),
            R::ERROR_OUT_OF_DEVICE_MEMORY | R::ERROR_OUT_OF_HOST_MEMORY => Error::Device(format!(
                "{call} ran out of {} memory (a smaller volume, frame or --size fits)",
                if result == R::ERROR_OUT_OF_DEVICE_MEMORY {
                    "device"
                } else {
                    "host"
                }
            )),
            result => Error::Vulkan { call, result },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_as_written_or_in_exponent_form_past_many_digits() {
        assert_eq!(number(250.0), "250");
        assert_eq!(number(-0.5), "-0.5");
        assert_eq!(number(0.0), "0");
        assert_eq!(number(1e300), "1e300");
        assert_eq!(number(-1e300), "-1e300");
        assert_eq!(number(1.5e-30), "1.5e-30");
        assert_eq!(number(f64::INFINITY), "inf");
        assert_eq!(
            (number(1e38f32), number(1e-38f32), number(0.1f32)),
            ("1e38".into(), "1e-38".into(), "0.1".into())
        );
    }
    use ash::vk;

    #[test]
    fn lost_devices_and_exhausted_memory_are_one_line_errors() {
        let lost = Err::<(), _>(vk::Result::ERROR_DEVICE_LOST)
            .vk("vkQueueSubmit2")
            .unwrap_err();
        assert!(matches!(lost, Error::Device(_)));
        assert_eq!(
            lost.to_string(),
            "the GPU device was lost in vkQueueSubmit2 (driver reset or watchdog; nothing was written)"
        );
        let oom = Err::<(), _>(vk::Result::ERROR_OUT_OF_DEVICE_MEMORY)
            .vk("vkAllocateMemory")
            .unwrap_err();
        assert!(
            oom.to_string().contains("vkAllocateMemory ran out of device memory"),
            "{oom}"
        );
        let other = Err::<(), _>(vk::Result::ERROR_INITIALIZATION_FAILED)
            .vk("vkCreateDevice")
            .unwrap_err();
        assert!(matches!(other, Error::Vulkan { .. }));
    }

    #[test]
    fn a_huge_echoed_input_is_cut_and_its_length_named() {
        let line = "é".repeat(1 << 20);
        let e = Error::invalid("header line", line.clone(), "unknown field").to_string();
        assert!(
            e.starts_with(&format!(
                "invalid header line '{}... (2097152 bytes in all)'",
                "é".repeat(200)
            )),
            "{}",
            &e[..300]
        );
        assert!(e.len() < 600, "{}", e.len());
        let f = Error::format("a.nrrd", format!("bad line '{line}'")).to_string();
        assert!(
            f.len() < 5000 && f.ends_with(&format!("({} bytes in all)", line.len() + 11)),
            "{}",
            &f[f.len() - 80..]
        );
        // Short text is untouched.
        assert_eq!(Error::invalid("x", "y", "z").to_string(), "invalid x 'y': z");
    }
}
