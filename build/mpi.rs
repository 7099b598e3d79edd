//! Feature `mpi`: compiles `src/parallel/icet_shim.c` against the system's
//! MPI (`mpicc --showme`, OpenMPI; else `pkg-config mpi`) and IceT's
//! headers, and links IceT's libraries with an rpath to where they are.
//!
//! IceT is found in `$LACUNA_ICET_DIR` (`include/IceT.h`, `lib/libvtkIceTCore*.so`),
//! else in `target/icet` (where `cargo xtask setup mpi` unpacks it from
//! Debian's `paraview` and `paraview-dev` packages without installing them),
//! else in an installed `paraview-dev`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn words(program: &str, args: &[&str]) -> Option<Vec<String>> {
    let out = Command::new(program).args(args).output().ok()?;
    out.status.success().then(|| {
        String::from_utf8_lossy(&out.stdout)
            .split_whitespace()
            .map(String::from)
            .collect()
    })
}

/// MPI's compile and link flags.
fn mpi_flags() -> (Vec<String>, Vec<String>) {
    if let (Some(c), Some(l)) = (
        words("mpicc", &["--showme:compile"]),
        words("mpicc", &["--showme:link"]),
    ) {
        return (c, l);
    }
    if let (Some(c), Some(l)) = (
        words("pkg-config", &["--cflags", "mpi"]),
        words("pkg-config", &["--libs", "mpi"]),
    ) {
        return (c, l);
    }
    panic!(
        "feature `mpi` needs an MPI implementation with mpicc (Debian: openmpi-bin libopenmpi-dev; \
         `cargo xtask setup mpi` installs them)"
    );
}

/// IceT's include and library folders.
fn icet_dirs(root: &Path) -> (PathBuf, PathBuf) {
    println!("cargo:rerun-if-env-changed=LACUNA_ICET_DIR");
    let mut candidates: Vec<(PathBuf, PathBuf)> = Vec::new();
    if let Ok(dir) = std::env::var("LACUNA_ICET_DIR") {
        let dir = PathBuf::from(dir);
        candidates.push((dir.join("include"), dir.join("lib")));
    }
    let local = root.join("target").join("icet");
    candidates.push((local.join("include"), local.join("lib")));
    if let Ok(entries) = std::fs::read_dir("/usr/include") {
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with("paraview-") {
                let lib = PathBuf::from("/usr/lib").join(format!("{}-linux-gnu", std::env::consts::ARCH));
                candidates.push((e.path().join("vtkicet/src/include"), lib));
            }
        }
    }
    for (include, lib) in candidates {
        if include.join("IceT.h").is_file() && core_library(&lib).is_some() {
            println!("cargo:rerun-if-changed={}", include.join("IceT.h").display());
            return (include, lib);
        }
    }
    panic!(
        "feature `mpi` needs IceT (headers and libvtkIceTCore/libvtkIceTMPI): run `cargo xtask setup mpi` \
         (unpacks Debian's paraview and paraview-dev into target/icet), install paraview-dev, \
         or set LACUNA_ICET_DIR to a folder with include/IceT.h and lib/"
    );
}

/// The link name of IceT's core library in `lib` (ParaView suffixes its
/// version: `vtkIceTCore-pv5.11`).
fn core_library(lib: &Path) -> Option<String> {
    let mut names: Vec<String> = std::fs::read_dir(lib)
        .ok()?
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let stem = name.strip_prefix("lib")?.strip_suffix(".so")?.to_string();
            (stem.starts_with("vtkIceTCore") || stem == "IceTCore").then_some(stem)
        })
        .collect();
    names.sort();
    names.pop()
}

pub fn build(root: &Path) {
    let shim = root.join("src/parallel/icet_shim.c");
    println!("cargo:rerun-if-changed={}", shim.display());
    let (compile, link) = mpi_flags();
    let (include, lib) = icet_dirs(root);
    let mut cc = cc::Build::new();
    cc.file(&shim).include(&include).warnings(true);
    for flag in &compile {
        match flag.strip_prefix("-I") {
            Some(dir) => cc.include(dir),
            None => cc.flag(flag),
        };
    }
    cc.compile("lacuna_icet_shim");
    let core = core_library(&lib).unwrap_or_default();
    let mpi_glue = core.replacen("Core", "MPI", 1);
    println!("cargo:rustc-link-search=native={}", lib.display());
    println!("cargo:rustc-link-lib=dylib={mpi_glue}");
    println!("cargo:rustc-link-lib=dylib={core}");
    println!("cargo:rustc-link-arg=-Wl,-rpath,{}", lib.display());
    for flag in &link {
        if let Some(dir) = flag.strip_prefix("-L") {
            println!("cargo:rustc-link-search=native={dir}");
            println!("cargo:rustc-link-arg=-Wl,-rpath,{dir}");
        } else if let Some(name) = flag.strip_prefix("-l") {
            println!("cargo:rustc-link-lib=dylib={name}");
        }
    }
}
