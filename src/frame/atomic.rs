//! Output files appear whole or not at all.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// The file an output at `path` replaces: a symbolic link's target (written
/// through, as `>` would), and an error where that exists and is no regular
/// file: the rename would put a file in a device's, pipe's or folder's place.
fn output_target(path: &Path) -> Result<PathBuf> {
    // `o.exr/` names a folder (its file name reads as `o.exr`): refused
    // here, before the work whose output the rename could not place.
    if path.as_os_str().to_string_lossy().ends_with(std::path::is_separator) {
        return Err(Error::invalid(
            "output path",
            path.display().to_string(),
            "ends in a separator, so it names a folder: give a file name",
        ));
    }
    let target = match std::fs::symlink_metadata(path) {
        // A dangling link names the file to create, beside the link.
        Ok(m) if m.file_type().is_symlink() => match std::fs::canonicalize(path) {
            Ok(t) => t,
            Err(_) => {
                let to = std::fs::read_link(path).map_err(|e| Error::io(path, e))?;
                path.parent().unwrap_or(Path::new(".")).join(to)
            }
        },
        _ => path.to_path_buf(),
    };
    match std::fs::metadata(&target) {
        Ok(m) if !m.is_file() => Err(Error::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                "exists and is not a regular file (a folder, device or pipe): lacuna replaces only regular files",
            ),
        )),
        _ => Ok(target),
    }
}

/// Writes to `path` (through a symbolic link to its target) via a sibling
/// temporary file and a rename; refuses to replace anything but a regular file.
pub fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let path = &output_target(path)?;
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or_else(|| Error::invalid("output path", path.display().to_string(), "has no file name"))?;
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    let result = write(&tmp).and_then(|_| std::fs::rename(&tmp, path).map_err(|e| crate::Error::io(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Fails before any work when an output's folder does not exist, or when
/// the output names something other than a regular file.
pub fn check_parent(path: &Path) -> Result<()> {
    let path = &output_target(path)?;
    let parent = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !parent.is_dir() {
        return Err(Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::NotFound, "its folder does not exist"),
        ));
    }
    // The folder takes a file (the temporary one the write makes there):
    // a read-only or full folder is found now, not after the work.
    let probe = parent.join(format!(".lacuna-probe.{}.tmp", std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        // Left by a process of this id that died: the folder took it.
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(Error::io(
            path,
            std::io::Error::new(e.kind(), format!("its folder takes no new file: {e}")),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("lacuna-atomic-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn refuses_what_is_not_a_regular_file_and_writes_through_links() {
        let dir = scratch("kinds");
        // A folder (as a device or pipe would be) is left in place.
        let folder = dir.join("out.exr");
        std::fs::create_dir(&folder).unwrap();
        for result in [check_parent(&folder), write_atomically(&folder, |_| Ok(()))] {
            let e = result.unwrap_err().to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
        assert!(folder.is_dir());
        // A name ending in a separator names a folder, existing or not.
        for name in ["new.exr/", "out.exr/"] {
            let e = check_parent(&PathBuf::from(format!("{}/{name}", dir.display())))
                .unwrap_err()
                .to_string();
            assert!(
                e.ends_with("ends in a separator, so it names a folder: give a file name"),
                "{e}"
            );
        }
        // A link to a file: the file gets the bytes, the link stays a link.
        let file = dir.join("real.txt");
        std::fs::write(&file, b"old").unwrap();
        let link = dir.join("link.txt");
        std::os::unix::fs::symlink(&file, &link).unwrap();
        check_parent(&link).unwrap();
        write_atomically(&link, |tmp| std::fs::write(tmp, b"new").map_err(|e| Error::io(tmp, e))).unwrap();
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&file).unwrap(), b"new");
        // A dangling link: its target is created.
        let dangling = dir.join("dangling.txt");
        std::os::unix::fs::symlink("made.txt", &dangling).unwrap();
        write_atomically(&dangling, |tmp| {
            std::fs::write(tmp, b"made").map_err(|e| Error::io(tmp, e))
        })
        .unwrap();
        assert_eq!(std::fs::read(dir.join("made.txt")).unwrap(), b"made");
        // A regular file is replaced whole.
        write_atomically(&file, |tmp| {
            std::fs::write(tmp, b"newer").map_err(|e| Error::io(tmp, e))
        })
        .unwrap();
        assert_eq!(std::fs::read(&link).unwrap(), b"newer");
        // The probe leaves the folder as it was.
        check_parent(&dir.join("new.exr")).unwrap();
        let mut names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        names.sort();
        assert_eq!(names, ["dangling.txt", "link.txt", "made.txt", "out.exr", "real.txt"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A folder that takes no file (procfs refuses new files, also to root)
    /// is found before any work.
    #[test]
    #[cfg(target_os = "linux")]
    fn a_folder_that_takes_no_file_is_refused_before_the_work() {
        let e = check_parent(Path::new("/proc/frame.exr")).unwrap_err().to_string();
        assert!(e.starts_with("/proc/frame.exr: its folder takes no new file"), "{e}");
    }
}
