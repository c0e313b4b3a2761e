//! `cota`: terrain level of detail from real DEMs.
//!
//! `main` stays boring: parse flags, call [`run`], print an error once.
#![recursion_limit = "256"]
use std::process::ExitCode;

use clap::Parser;

/// `writeln!` into a `String` report (which cannot fail).
macro_rules! say {
    ($s:expr, $($t:tt)*) => {{
        use std::fmt::Write as _;
        let _ = writeln!($s, $($t)*);
    }};
}

mod args;
mod compare;
mod hole;
mod imagery;
mod info;
mod input;
mod mesh;
mod output;
mod pair;
mod print;
mod progress;
mod serve;
mod stream;
mod tiles;
mod tiles_estimate;
mod tiles_part;
mod window;

fn main() -> ExitCode {
    quiet_broken_pipe();
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("cota: error: {}", error_text(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, joined by ": ", each cause once: a cause whose
/// text an outer error already printed (an I/O error its wrapper quotes) is
/// not printed again, nor a path the outer error ends with.
fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let mut t = cause.to_string();
        // "writing /x" then "/x: No such file…": the path once.
        if let Some((head, rest)) = t.split_once(": ") {
            if !head.is_empty() && text.ends_with(head) {
                t = rest.to_string();
            }
        }
        if text.contains(&t) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&t);
    }
    text
}

fn run() -> anyhow::Result<ExitCode> {
    let cli = args::Cli::parse();
    progress::set_quiet(cli.quiet);
    match cli.command {
        args::Command::Info(a) => info::run(&a),
        args::Command::Mesh(a) => mesh::run(&a),
        args::Command::Compare(a) => compare::run(&a),
        args::Command::Pair(a) => pair::run(&a),
        args::Command::Stream(c) => stream::run(&c),
        args::Command::Tiles(a) => tiles::run(&a),
        args::Command::Serve(a) => serve::run(&a),
    }
}

/// `cota info … | head` closes stdout early; `println!` then panics with
/// "failed printing to stdout: Broken pipe". That is not an error of cota's:
/// exit 0 quietly, as other Unix tools do. Every other panic keeps the default
/// report.
fn quiet_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let msg = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.contains("failed printing to stdout") && msg.contains("Broken pipe") {
            std::process::exit(0);
        }
        default(info);
    }));
}
