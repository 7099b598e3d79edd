//! `cargo run --example embed -- [--out embed.exr] [--validate]`: a host
//! engine that embeds lacuna (see engine.rs and README "Embedding").

mod engine;
mod host;

use std::path::PathBuf;

fn main() {
    let mut out = PathBuf::from("embed.exr");
    let mut settings = engine::Settings::default();
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--validate" => settings.validate = true,
            "--out" => match args.next() {
                Some(p) => out = p.into(),
                None => fail("--out needs a path"),
            },
            other => fail(&format!("unknown argument '{other}' (expected --out PATH, --validate)")),
        }
    }
    let rendered = engine::run(&settings).unwrap_or_else(|e| fail(&e));
    if let Err(e) = rendered.composite.write_exr(&out) {
        fail(&e.to_string());
    }
    let ms = |name| {
        rendered
            .timings
            .phase(name)
            .map_or("-".to_string(), |v| format!("{v:.2} ms"))
    };
    let cube = rendered.depth.iter().filter(|&&d| d < 1.0).count();
    let volume = rendered.volume.pixels.iter().filter(|p| p[3] > 0.0).count();
    let lit = rendered.mesh.pixels.iter().filter(|p| p[3] > 0.0).count();
    println!(
        "wrote {} ({}x{}): cube {cube} pixels ({lit} lit), volume {volume} pixels; build classify {}, march {}; lacuna's own submissions {}",
        out.display(),
        settings.size,
        settings.size,
        ms("classify"),
        ms("march"),
        rendered.lacuna_submissions
    );
    if !rendered.validation.is_empty() {
        for m in &rendered.validation {
            eprintln!("{m}");
        }
        fail(&format!("{} validation message(s)", rendered.validation.len()));
    }
}

fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    std::process::exit(1);
}
