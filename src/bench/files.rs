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
