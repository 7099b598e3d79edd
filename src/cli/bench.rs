//! `lacuna bench`: the paper's comparison, speed against error, the hard-case suite.

use super::{check_parent, context, validation_verdict};
use clap::Args;
use lacuna::{Error, Result};
use std::path::{Path, PathBuf};
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
    /// Compare two runs' results.json (A then B): per record the ratio of median frame times, and the
    /// fastest structure per data set; exit 1 when a median moved more than --tolerance or the fastest differs.
    #[arg(long, num_args = 2, value_names = ["A", "B"])]
    compare: Option<Vec<PathBuf>>,
    /// Largest relative change of a median --compare accepts.
    #[arg(long, default_value_t = 0.2, requires = "compare", allow_hyphen_values = true)]
    tolerance: f64,
    /// Run a suite instead: "hard" (the DESIGN hard cases for every structure; exit 1 on failure) or
    /// "auto" (bench/auto.toml, then auto's contract per data set: at least 0.95x naive, within 10 % of
    /// the fastest exact structure; exit 1 when broken).
    #[arg(long)]
    suite: Option<String>,
    /// With --suite hard: only this look (composite, "shaded, jittered", mip, minip, average,
    /// "iso, jittered"); repeatable. Default: every look.
    #[arg(long, requires = "suite")]
    look: Vec<String>,
    /// With --suite hard: only this case (its name as the table shows it, e.g. "grazing rays");
    /// repeatable. Default: every case.
    #[arg(long, requires = "suite")]
    case: Vec<String>,
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
    /// Override the config's least untimed warm-up frames and builds per structure.
    #[arg(long)]
    warmup: Option<u32>,
    /// Override the config's interleaved timing rounds per view (at least 2).
    #[arg(long)]
    rounds: Option<u32>,
    /// Early ray termination threshold for the timed frames (default: the config's, usually off).
    #[arg(long)]
    ert: Option<f32>,
    /// Sample filter of the timed frames, manual or hardware (default: the config's, else the device's faster).
    #[arg(long)]
    filter: Option<lacuna::render::Filter>,
    /// Write frame 0 of every run as EXR under OUT/frames.
    #[arg(long)]
    frames_out: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Enable Vulkan validation (the hard-case suite always does).
    #[arg(long)]
    validate: bool,
    #[command(flatten)]
    model: super::args::ModelArgs,
}

pub fn run(args: &BenchArgs) -> Result<ExitCode> {
    use lacuna::bench::{self, BenchConfig};
    let sources = args.config.is_some() as u32
        + args.quick as u32
        + args.paper as u32
        + args.suite.is_some() as u32
        + args.compare.is_some() as u32;
    if sources != 1 {
        return Err(Error::invalid(
            "bench",
            format!("{sources} sources"),
            "give exactly one of: a config file, --quick, --paper, --suite hard, --suite auto, --compare A B",
        ));
    }
    check_unused(args)?;
    if let Some(paths) = &args.compare {
        return compare(&paths[0], &paths[1], args.tolerance);
    }
    let auto_suite = args.suite.as_deref() == Some("auto");
    if let Some(suite) = args.suite.as_ref().filter(|_| !auto_suite) {
        if suite != "hard" {
            return Err(Error::invalid("suite", suite, "expected hard or auto"));
        }
        let only = bench::hard::Selection {
            looks: args.look.clone(),
            cases: args.case.clone(),
        };
        only.check()?;
        let ctx = context(true)?;
        let progress = !args.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr());
        let outcomes = bench::hard::run(&ctx, &only, |case| {
            if progress {
                say_err!("hard case: {case}");
            }
        })?;
        say!("device {} ({})", ctx.info().name, ctx.info().driver);
        say!("{}", bench::hard::table(&outcomes));
        let failed: Vec<_> = outcomes.iter().filter(|o| !o.passed()).collect();
        for o in &failed {
            say!(
                "FAIL {} / {} / {} / {}: identical {}, validation messages {}, finite {}; {}",
                o.case,
                o.look,
                o.filter,
                o.structure,
                o.identical,
                o.validation_messages,
                o.finite,
                o.detail
            );
        }
        let naive = outcomes.iter().filter(|o| o.mode_fallback).count();
        say!(
            "hard cases: {} of {} structure runs passed ({} of them in a mode the structure does not skip in, marched naively: the table's `naive`; `pass (KERNEL)`: another kernel marched it, as a tree of one leaf)",
            outcomes.len() - failed.len(),
            outcomes.len(),
            naive
        );
        return Ok(if failed.is_empty() {
            ExitCode::SUCCESS
        } else {
            ExitCode::from(1)
        });
    }
    // Overridden, then validated: `--rounds 2` mends a file's `rounds = 1`.
    let (mut config, origin) = match &args.config {
        Some(path) => (BenchConfig::load_unchecked(path)?, path.display().to_string()),
        None => {
            let (text, origin) = match (args.quick, auto_suite) {
                (true, _) => (bench::config::QUICK, "bench/quick.toml (built in)"),
                (_, true) => (bench::config::AUTO, "bench/auto.toml (built in)"),
                _ => (bench::config::PAPER, "bench/paper.toml (built in)"),
            };
            (BenchConfig::parse_unchecked(text, origin)?, origin.to_string())
        }
    };
    match override_protocol(args, &mut config) {
        true => config.validate(&format!("{origin} with the command line's overrides"))?,
        false => config.validate(&origin)?,
    }
    if args.frames_out {
        config.check_frame_files(&origin)?;
    }
    bench::preflight::check(&config, &origin)?;
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("bench/out").join(&config.name));
    check_out_dir(&out_dir)?;
    let ctx = context(args.validate)?;
    let output = bench::run::run(
        &ctx,
        &config,
        &bench::RunOptions {
            quiet: args.quiet,
            keep_frames: args.frames_out,
            cost_cache: lacuna::accel::auto::cache::default_folder(),
            recalibrate: args.model.recalibrate,
        },
    )?;
    if output.records.is_empty() {
        return Err(Error::format(
            &origin,
            "every data set was skipped (optional, and its file missing): nothing was measured",
        ));
    }
    // auto's contract, written with the run's other files.
    let contract = auto_suite.then(|| bench::contract::markdown(&bench::contract::verdicts(&output.records)));
    let extra: Vec<(&str, String)> = contract
        .iter()
        .map(|(table, _)| ("contract.md", table.clone()))
        .collect();
    let written = bench::write_outputs(&out_dir, &output, &extra)?;
    say!("device {} ({})", ctx.info().name, ctx.info().driver);
    say!(
        "config {}: {}x{}, {} views x {} interleaved rounds, step {}, ERT {}, filter {}, {} interleaved builds per structure, \
         warm-up until two consecutive times agree within {}% (at least {}, at most {})",
        config.name,
        config.size[0],
        config.size[1],
        config.frames,
        config.rounds,
        config.step,
        config.ert.map_or("off".into(), |e| e.to_string()),
        config.filter.as_deref().unwrap_or("the device's faster"),
        config.builds,
        config.stable * 100.0,
        config.warmup.max(2),
        config.warmup_cap
    );
    say!();
    say!("{}", bench::tables::table2_md(&output.records));
    say!("{}", bench::tables::frames_md(&output.records));
    say!("{}", bench::tables::table1_md(&output.records));
    say!("{}", bench::tables::exactness_md(&output.records));
    if !output.steps.is_empty() {
        say!("{}", output.steps_md());
    }
    for r in bench::tables::fastest(&output.records) {
        say!(
            "fastest on {}: {} ({:.2} ms median, {:.2}x naive{})",
            r.dataset,
            r.structure,
            r.frame.median_ms,
            r.speedup,
            if r.unstable { ", unstable" } else { "" }
        );
    }
    for note in &output.notes {
        say!("note: {note}");
    }
    let mut contract_held = true;
    if let Some((table, passed)) = contract {
        say!("{table}");
        say!("wrote {}", out_dir.join("contract.md").display());
        contract_held = passed;
    }
    say!("wrote {} files to {}", written.len(), out_dir.display());
    let verdict = validation_verdict(&ctx);
    Ok(if contract_held { verdict } else { ExitCode::from(1) })
}

fn read_records(path: &Path) -> Result<Vec<lacuna::bench::Record>> {
    let text = lacuna::limits::read_input_text(path, "bench results.json", lacuna::limits::MAX_TEXT_INPUT)?;
    let records: Vec<lacuna::bench::Record> =
        serde_json::from_str(&text).map_err(|e| Error::format(path, format!("not a bench results.json: {e}")))?;
    // What a run writes: positive finite times, one record per data set
    // and structure; anything else would compare as NaN or pass unseen.
    let mut seen = std::collections::HashSet::new();
    for r in &records {
        let what = format!("{} / {}", r.dataset, r.structure);
        if !(r.frame.median_ms.is_finite() && r.frame.median_ms > 0.0) {
            return Err(Error::format(
                path,
                format!("{what}: median_ms {} is not a positive time", r.frame.median_ms),
            ));
        }
        if !seen.insert((&r.dataset, &r.structure)) {
            return Err(Error::format(path, format!("{what} appears twice")));
        }
    }
    Ok(records)
}

fn compare(a: &Path, b: &Path, tolerance: f64) -> Result<ExitCode> {
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(Error::invalid(
            "tolerance",
            tolerance.to_string(),
            "must be a finite number >= 0",
        ));
    }
    let (ra, rb) = (read_records(a)?, read_records(b)?);
    let c = lacuna::bench::compare::Comparison::new(&ra, &rb);
    if c.rows.is_empty() {
        return Err(Error::invalid(
            "compare",
            format!("{} and {}", a.display(), b.display()),
            "no data set x structure is in both runs",
        ));
    }
    // Runs of different frames measure different work: no verdict.
    if let Some((record, fields)) = c.mismatched.first() {
        let others = match c.mismatched.len() - 1 {
            0 => String::new(),
            n => format!(" (and {n} more records)"),
        };
        return Err(Error::invalid(
            "compare",
            format!("{} and {}", a.display(), b.display()),
            format!(
                "the runs rendered different frames: {record}: {}{others}",
                fields.join(", ")
            ),
        ));
    }
    for note in &c.notes {
        say!("note: the runs differ in {note}");
    }
    say!("{}", c.markdown(&a.display().to_string(), &b.display().to_string()));
    let ok = c.worst() <= tolerance && c.same_fastest() && c.complete();
    say!(
        "{}: every median within {:.0} %, the same (or a tied) fastest structure per data set, and every record in both runs",
        if ok { "PASS" } else { "FAIL" },
        100.0 * tolerance
    );
    Ok(if ok { ExitCode::SUCCESS } else { ExitCode::from(1) })
}

/// Sets the protocol fields the command line gives; whether it gave any.
fn override_protocol(args: &BenchArgs, config: &mut lacuna::bench::BenchConfig) -> bool {
    if let Some(f) = args.frames {
        config.frames = f;
    }
    if let Some((w, h)) = args.size {
        config.size = [w, h];
    }
    if let Some(b) = args.builds {
        config.builds = b;
    }
    if let Some(w) = args.warmup {
        config.warmup = w;
        config.warmup_cap = config.warmup_cap.max(w);
    }
    if let Some(r) = args.rounds {
        config.rounds = r;
    }
    if args.ert.is_some() {
        config.ert = args.ert;
    }
    if let Some(f) = args.filter {
        config.filter = Some(f.to_string());
    }
    args.frames.is_some()
        || args.size.is_some()
        || args.builds.is_some()
        || args.warmup.is_some()
        || args.rounds.is_some()
        || args.ert.is_some()
        || args.filter.is_some()
}

/// Refuses an option the chosen source does not read, naming it: a run's
/// protocol options mean nothing to --compare (which runs nothing) or to
/// the hard suite (whose cases fix their own frames), and --look and
/// --case choose among the hard suite's.
fn check_unused(args: &BenchArgs) -> Result<()> {
    let protocol = [
        ("--out", args.out.is_some()),
        ("--frames", args.frames.is_some()),
        ("--size", args.size.is_some()),
        ("--builds", args.builds.is_some()),
        ("--warmup", args.warmup.is_some()),
        ("--rounds", args.rounds.is_some()),
        ("--ert", args.ert.is_some()),
        ("--filter", args.filter.is_some()),
        ("--frames-out", args.frames_out),
    ];
    let hard = args.suite.as_deref() == Some("hard");
    let (given, why) = if args.compare.is_some() {
        let mut unused = protocol.to_vec();
        unused.extend([("--recalibrate", args.model.recalibrate), ("--validate", args.validate)]);
        (unused, "--compare reads two results.json and runs nothing")
    } else if hard {
        let mut unused = protocol.to_vec();
        unused.push(("--recalibrate", args.model.recalibrate));
        (
            unused,
            "the hard suite's cases fix their own frames, price auto with nominal constants and write no files",
        )
    } else {
        let unused = vec![("--look", !args.look.is_empty()), ("--case", !args.case.is_empty())];
        (
            unused,
            "it chooses among the hard suite's looks and cases (--suite hard)",
        )
    };
    match given.iter().find(|(_, on)| *on) {
        Some((flag, _)) => Err(Error::invalid("option", *flag, why)),
        None => Ok(()),
    }
}

/// Refuses an output folder that is (or lies under) a file before the run,
/// not after it: the nearest part of it that exists must be a folder.
/// That folder must take a new file too (read-only or full: found now).
fn check_out_dir(dir: &Path) -> Result<()> {
    match dir.ancestors().find(|p| p.as_os_str().is_empty() || p.exists()) {
        Some(p) if !p.as_os_str().is_empty() && !p.is_dir() => Err(Error::io(
            p,
            std::io::Error::new(std::io::ErrorKind::AlreadyExists, "exists and is not a folder"),
        )),
        Some(p) => check_parent(&p.join("results.json")),
        None => Ok(()),
    }
}
