//! `lacuna bench`: the paper's comparison, speed against error, the hard-case suite.

use super::{context, validation_verdict};
use clap::Args;
use lacuna::{Error, Result};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct BenchArgs {
    /// A benchmark config (TOML), like bench/quick.toml or bench/paper.toml.
    config: Option<PathBuf>,
    /// The built-in quick config (bench/quick.toml): every structure, small data, about 2 minutes on lavapipe.
    #[arg(long)]
    quick: bool,
    /// The built-in paper config (bench/paper.toml): the paper's grid of data sets x structures.
    #[arg(long)]
    paper: bool,
    /// Run a test suite instead: "hard" (the DESIGN hard cases for every structure; exit 1 on failure).
    #[arg(long)]
    suite: Option<String>,
    /// Output folder (default bench/out/<config name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Override the config's number of views.
    #[arg(long)]
    frames: Option<u32>,
    /// Override the config's frame size (WxH).
    #[arg(long, value_parser = lacuna::render::parse_size)]
    size: Option<(u32, u32)>,
    /// Override the config's timed builds per structure.
    #[arg(long)]
    builds: Option<u32>,
    /// Override the config's untimed warm-up frames and builds.
    #[arg(long)]
    warmup: Option<u32>,
    /// Write frame 0 of every run as EXR under OUT/frames.
    #[arg(long)]
    frames_out: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Enable Vulkan validation (the hard-case suite always does).
    #[arg(long)]
    validate: bool,
}

pub fn run(args: &BenchArgs) -> Result<ExitCode> {
    use lacuna::bench::{self, BenchConfig};
    let sources = args.config.is_some() as u32 + args.quick as u32 + args.paper as u32 + args.suite.is_some() as u32;
    if sources != 1 {
        return Err(Error::invalid(
            "bench",
            format!("{sources} sources"),
            "give exactly one of: a config file, --quick, --paper, --suite hard",
        ));
    }
    if let Some(suite) = &args.suite {
        if suite != "hard" {
            return Err(Error::invalid("suite", suite, "expected hard"));
        }
        let ctx = context(true)?;
        let progress = !args.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr());
        let outcomes = bench::hard::run(&ctx, |case| {
            if progress {
                eprintln!("hard case: {case}");
            }
        })?;
        println!("device {} ({})", ctx.info().name, ctx.info().driver);
        println!("{}", bench::hard::table(&outcomes));
        let failed: Vec<_> = outcomes.iter().filter(|o| !o.passed()).collect();
        for o in &failed {
            println!(
                "FAIL {} / {}: identical {}, validation messages {}, finite {}; {}",
                o.case, o.structure, o.identical, o.validation_messages, o.finite, o.detail
            );
        }
        println!(
            "hard cases: {} of {} structure runs passed",
            outcomes.len() - failed.len(),
            outcomes.len()
        );
        return Ok(if failed.is_empty() {
            ExitCode::SUCCESS
        } else {
            ExitCode::from(1)
        });
    }
    let mut config = match (&args.config, args.quick) {
        (Some(path), _) => BenchConfig::load(path)?,
        (None, true) => BenchConfig::parse(bench::config::QUICK, "bench/quick.toml (built in)")?,
        (None, false) => BenchConfig::parse(bench::config::PAPER, "bench/paper.toml (built in)")?,
    };
    if let Some(f) = args.frames {
        if f == 0 {
            return Err(Error::invalid("frames", "0", "must be at least 1"));
        }
        config.frames = f;
    }
    if let Some((w, h)) = args.size {
        config.size = [w, h];
    }
    if let Some(b) = args.builds {
        if b == 0 {
            return Err(Error::invalid("builds", "0", "must be at least 1"));
        }
        config.builds = b;
    }
    if let Some(w) = args.warmup {
        config.warmup = w;
    }
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("bench/out").join(&config.name));
    let ctx = context(args.validate)?;
    let output = bench::run::run(
        &ctx,
        &config,
        &bench::RunOptions {
            quiet: args.quiet,
            keep_frames: args.frames_out,
        },
    )?;
    let written = bench::write_outputs(&out_dir, &output)?;
    println!("device {} ({})", ctx.info().name, ctx.info().driver);
    println!(
        "config {}: {}x{}, {} views after {} warm-up, step {}, {} builds per structure",
        config.name, config.size[0], config.size[1], config.frames, config.warmup, config.step, config.builds
    );
    println!();
    println!("{}", bench::tables::table2_md(&output.records));
    println!("{}", bench::tables::table1_md(&output.records));
    println!("{}", bench::tables::exactness_md(&output.records));
    for note in &output.notes {
        println!("note: {note}");
    }
    println!("wrote {} files to {}", written.len(), out_dir.display());
    Ok(validation_verdict(&ctx))
}
