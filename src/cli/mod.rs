//! The native command line over the same pipeline as the browser app (see `main.rs`), on clap:
//! the arguments every method shares (`args.rs`), one subcommand per method and its one generic
//! driver (`methods.rs`), `info`, the input and output files, the progress line, and the Node
//! bridge for Rhino files.
//!
//! Conventions: `--help` per command, `--version`; results on stdout, warnings and a live
//! progress line on stderr (on a terminal a live line, elsewhere JSON lines once a second after
//! the first second; never with `--quiet`); an error
//! is one line on stderr (one JSON object with `--json`). Exit codes: see [`EXIT_CODES`].

mod args;
mod files;
mod info;
mod methods;
mod outcome;
mod progress;
mod rhino;

use std::io::IsTerminal;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use spherical_faces::text::printable;

use args::Input;
use methods::MethodCommand;
use outcome::{Failure, EXIT_CODES};
use progress::{ProgressLine, ProgressMode};

#[derive(Parser)]
#[command(name = "spherical-faces", version, about = "Approximates a free-form surface by a mesh of spherical panels \
(Approximation by Meshes with Spherical Faces).", after_help = EXIT_CODES)]
struct Cli {
    /// No progress on stderr (a live line on a terminal, otherwise one JSON object a second).
    #[arg(long, short, global = true)]
    quiet: bool,
    /// Errors as one JSON object on stderr, for scripts.
    #[arg(long, global = true)]
    json: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Counts after welding, mean curvature (jet-fitted on a mesh, exact on a B-spline) and, for a
    /// B-spline, its degrees, control grid, domain and curvature ranges: one JSON object. With
    /// --list-objects, the objects of a .3dm file instead.
    #[command(after_help = EXIT_CODES)]
    Info {
        #[command(flatten)]
        input: Input,
        /// List the objects of a .3dm file (one JSON object per line) and stop.
        #[arg(long)]
        list_objects: bool,
    },
    #[command(flatten)]
    Method(MethodCommand),
}

pub fn main() -> ExitCode {
    let json = std::env::args().any(|a| a == "--json");
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                print!("{}", e.render());
                return ExitCode::SUCCESS;
            }
            if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                eprint!("{}", e.render());
                return ExitCode::from(2);
            }
            // One line: clap's message up to its usage, without its prefix, and where to look.
            let text = e.render().to_string();
            let message: Vec<&str> = text
                .lines()
                .map(str::trim)
                .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
                .filter(|l| !l.is_empty() && !l.starts_with("tip:"))
                .collect();
            let message = message.join(" ");
            return fail(json, &Failure::input(format!("{} (see --help)", message.trim_start_matches("error: "))));
        }
    };
    let mode = match (cli.quiet, std::io::stderr().is_terminal()) {
        (true, _) => ProgressMode::Off,
        (false, true) => ProgressMode::Line,
        (false, false) => ProgressMode::JsonLines,
    };
    let mut progress = ProgressLine::new(mode);
    let result = match cli.command {
        Command::Info { input, list_objects } => info::info(&input, list_objects),
        Command::Method(method) => method.run(&mut progress),
    };
    progress.clear();
    match result {
        Ok(out) => {
            println!("{out}");
            ExitCode::SUCCESS
        }
        Err(f) => fail(json, &f),
    }
}

/// Prints the failure (one line, or one JSON object) and gives its exit code.
fn fail(json: bool, f: &Failure) -> ExitCode {
    let message = printable(&f.message);
    if json {
        eprintln!("{}", serde_json::json!({ "error": message, "exit_code": f.code }));
    } else {
        eprintln!("error: {message}");
    }
    ExitCode::from(f.code)
}
