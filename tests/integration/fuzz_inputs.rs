//! The fuzz targets' seeds and every crash input the fuzzers found
//! (`fuzz/regressions/TARGET/`), run through the same functions on stable:
//! no panic, one-line errors, and each seed parses unless it is named `bad*`.

#[path = "../../fuzz/src/lib.rs"]
mod targets;

use std::path::Path;

type Target = fn(&[u8]) -> bool;

const TARGETS: [(&str, Target); 7] = [
    ("volume_spec", targets::volume_spec),
    ("raw", targets::raw),
    ("nrrd", targets::nrrd),
    ("nifti", targets::nifti),
    ("tf", targets::tf),
    ("bench_toml", targets::bench_toml),
    ("exr", targets::exr),
];

/// Files of `dir` (none when it does not exist), sorted.
fn inputs(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    files.sort();
    files
}

#[test]
fn seeds_parse_unless_named_bad() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds");
    for (name, target) in TARGETS {
        let files = inputs(&root.join(name));
        assert!(!files.is_empty(), "no seeds for {name}");
        for f in files {
            let bad = f.file_name().is_some_and(|n| n.to_string_lossy().starts_with("bad"));
            let parsed = target(&std::fs::read(&f).unwrap());
            assert_eq!(parsed, !bad, "{name}: {}", f.display());
        }
    }
}

#[test]
fn crash_inputs_are_errors_not_panics() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions");
    for (name, target) in TARGETS {
        for f in inputs(&root.join(name)) {
            // Each was a crash (panic, abort or unbounded allocation); now
            // a one-line error (the target asserts one line).
            assert!(!target(&std::fs::read(&f).unwrap()), "{name}: {} parsed", f.display());
        }
    }
}
