//! Where a run's files go under its output folder.

use std::path::PathBuf;

/// The file (under the output folder) of a data set's frame 0 with a
/// structure: `frames/SLUG.exr`, where a slug past 200 bytes (a look with
/// six clip planes) keeps its first 180 and a hash of the whole name, as
/// file names end at 255 bytes.
pub fn frame_file(dataset: &str, structure: &str) -> String {
    let name = format!("{dataset}-{structure}");
    let slug = slug(&name).display().to_string();
    let slug = match slug.len() > 200 {
        // FNV-1a: stable across runs and builds, unlike the std hasher.
        true => {
            let hash = name.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
                (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
            });
            format!("{}~{hash:016x}", &slug[..180])
        }
        false => slug,
    };
    format!("frames/{slug}.exr")
}

/// A label as a file name: characters other than ASCII letters, digits,
/// `-` and `.` become `_`.
pub fn slug(s: &str) -> PathBuf {
    PathBuf::from(
        s.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '.' {
                    c
                } else {
                    '_'
                }
            })
            .collect::<String>(),
    )
}

#[cfg(test)]
mod tests {
    use super::frame_file;

    #[test]
    fn long_frame_names_keep_a_prefix_and_a_stable_hash_and_stay_apart() {
        assert_eq!(
            frame_file("nbody:8 [shade]", "grid 8"),
            "frames/nbody_8__shade_-grid_8.exr"
        );
        let clip = "clip 1,0,0,-4; ".repeat(20);
        let (a, b) = (frame_file(&clip, "grid"), frame_file(&clip, "lbvh"));
        let prefix = format!("frames/{}", &super::slug(&clip).display().to_string()[..180]);
        for f in [&a, &b] {
            // 180 bytes of slug, `~`, 16 hex digits, `.exr`: under 255.
            assert!(f.starts_with(&prefix) && f.len() == prefix.len() + 1 + 16 + 4, "{f}");
        }
        assert_ne!(a, b, "two structures, two files");
        assert_eq!(a, frame_file(&clip, "grid"), "the same name every run");
    }
}
