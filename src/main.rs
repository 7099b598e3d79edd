//! The `lacuna` command line: parses the arguments and dispatches to the
//! command's module in `cli/`; every command is a thin layer over the library.

#[macro_use]
mod cli;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "lacuna",
    version,
    about = "Vulkan direct volume renderer for comparing empty space skipping structures"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render one frame and print GPU time per pass.
    Render(Box<cli::render::RenderArgs>),
    /// Describe a volume: dims, type, spacing, values; occupancy under a TF.
    Info(cli::info::InfoArgs),
    /// Write a volume (file or generator) as an Open SciVis raw file in its source units.
    Export(cli::export::ExportArgs),
    /// Compare two EXR frames (exit 1 if --max-abs is exceeded, 2 on bad input).
    Diff(cli::diff::DiffArgs),
    /// List Vulkan devices (select one with LACUNA_DEVICE=<index or name>).
    Devices,
    /// Benchmark every structure (the paper's comparison), speed against error, or the hard-case suite.
    Bench(cli::bench::BenchArgs),
    /// Generate an SPD surface scene; print its primitive counts, optionally write NFF.
    Scene(cli::scene::SceneArgs),
    /// Havran's octree comparison on the SPD scenes: build, trace (Whitted), print his statistics.
    Octree(Box<cli::octree::OctreeArgs>),
    /// Look at a volume in a window: orbit, zoom, pan; change the TF, structure, ERT, step.
    #[cfg(feature = "view")]
    View(Box<cli::view::ViewArgs>),
}

fn main() -> ExitCode {
    // `lacuna info ... | head` ends quietly, as other Unix tools do.
    cli::stdout::end_at_a_closed_pipe();
    // Under mpirun, an error every rank meets alike is said by rank 0 alone.
    let echo = lacuna::parallel::launched_rank().is_none_or(|r| r == 0);
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            let help = matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            );
            if help {
                let _ = e.print();
                let missing = e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand;
                return ExitCode::from(if missing { 2 } else { 0 });
            }
            // One line: clap's first line names the bad argument, or ends in
            // ':' with the arguments (missing ones) indented below it.
            let text = e.render().to_string();
            let mut lines = text.lines();
            let mut line = lines.next().unwrap_or("error: invalid arguments").to_string();
            if line.ends_with(':') {
                let listed: Vec<&str> = lines
                    .take_while(|l| l.starts_with(char::is_whitespace))
                    .map(str::trim)
                    .collect();
                line = format!("{line} {}", listed.join(", "));
            }
            if echo {
                say_err!("{}", line.trim_end());
            }
            return ExitCode::from(2);
        }
    };
    let ranks = lacuna::parallel::across_ranks(lacuna::parallel::launched_ranks(), lacuna::parallel::ENABLED);
    let (result, echo) = match (&cli.command, ranks) {
        (_, Err(e)) => (Err(e), echo),
        // The ranks agree which of them says why (`cli/ranks.rs`).
        #[cfg(feature = "mpi")]
        (Command::Render(a), Ok(true)) => (cli::ranks::run(a), true),
        (_, Ok(true)) => (
            Err(lacuna::Error::invalid(
                "command",
                "under mpirun",
                "only `lacuna render` renders across ranks",
            )),
            echo,
        ),
        (command, Ok(false)) => (dispatch(command), true),
    };
    // Lines that could not be written (a full disk) fail the command, after
    // its work; a closed pipe does not.
    let printed = cli::stdout::finish();
    let result = result.and_then(|code| printed.map(|()| code));
    match result {
        Ok(code) => code,
        Err(e) => {
            if echo {
                // One line whatever a path or value held (a newline in a
                // file name would start a second).
                say_err!("error: {}", lacuna::error::one_line(e.to_string()));
            }
            ExitCode::from(2)
        }
    }
}

fn dispatch(command: &Command) -> lacuna::Result<ExitCode> {
    match command {
        Command::Render(a) => cli::render::run(a),
        Command::Info(a) => cli::info::run(a),
        Command::Export(a) => cli::export::run(a),
        Command::Diff(a) => cli::diff::run(a),
        Command::Devices => cli::devices::run(),
        Command::Bench(a) => cli::bench::run(a),
        Command::Scene(a) => cli::scene::run(a),
        Command::Octree(a) => cli::octree::run(a),
        #[cfg(feature = "view")]
        Command::View(a) => cli::view::run(a),
    }
}
