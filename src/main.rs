//! `seat-twin`: with no subcommand it opens the desktop app (feature `gui`); the subcommands
//! run the same engine headless. This file parses and dispatches; each subcommand lives in
//! its own file under `src/cli/`.

use anyhow::Result;
use clap::Parser;
use seat_twin::cli::{self, Cli};
use seat_twin::fsutil;

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        None => open_app().map(|()| cli::Outcome::Done),
        Some(cmd) => {
            clean_up_on_signals();
            cli::run(&cmd)
        }
    };
    // The exit codes are documented in the README (CLI section) and in `cli`.
    let code = match result {
        Ok(outcome) => outcome.exit_code(),
        Err(e) => {
            eprintln!("error: {}", cli::error_text(&e));
            cli::EXIT_ERROR
        }
    };
    if code != 0 {
        std::process::exit(code);
    }
}

/// On SIGINT, SIGTERM or SIGHUP: removes the temporary files and folders of the output being
/// written ([`fsutil::remove_pending`]), says so, and exits with 128 + the signal's number.
#[cfg(unix)]
fn clean_up_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    use std::io::Write;
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(sig) = signals.forever().next() {
            let removed = fsutil::remove_pending();
            let name = match sig {
                SIGINT => "SIGINT",
                SIGTERM => "SIGTERM",
                _ => "SIGHUP",
            };
            // Not eprintln!: with stderr closed (`| head`) it would panic, and this thread
            // would never reach the exit.
            let _ = writeln!(
                std::io::stderr(),
                "\ninterrupted ({name}): stopped{}",
                if removed > 0 {
                    "; the unfinished output was removed"
                } else {
                    ""
                }
            );
            std::process::exit(128 + sig);
        }
    });
}

#[cfg(not(unix))]
fn clean_up_on_signals() {}

#[cfg(feature = "gui")]
fn open_app() -> Result<()> {
    seat_twin::gui::run_native().map_err(|e| anyhow::anyhow!("the app could not start: {e}"))
}

#[cfg(not(feature = "gui"))]
fn open_app() -> Result<()> {
    use clap::CommandFactory;
    Cli::command().print_help()?;
    println!("\n\n(built without the `gui` feature: use a subcommand)");
    Ok(())
}
