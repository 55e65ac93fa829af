//! The `tilth` binary: parse the arguments, run the command, map errors to exit codes
//! (see the library's documentation).

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    tilth::memory::return_large_blocks();
    let cli = tilth::cli::Cli::parse();
    match tilth::cli::execute(cli, &mut std::io::stdout().lock()) {
        Ok(()) => ExitCode::from(tilth::EXIT_OK),
        Err(e) if tilth::is_broken_pipe(&e) => ExitCode::from(tilth::EXIT_OK),
        Err(e) => {
            eprintln!("error: {}", format!("{e:#}").trim_end());
            ExitCode::from(tilth::exit_code(&e))
        }
    }
}
