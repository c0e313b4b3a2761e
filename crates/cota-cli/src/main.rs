//! `cota`: terrain level of detail from real DEMs.
//!
//! `main` stays boring: parse flags, call [`run`], print an error once.
use std::process::ExitCode;

use clap::Parser;

mod args;
mod compare;
mod info;
mod input;
mod mesh;
mod progress;
mod refine;
mod stream;

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("cota: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> anyhow::Result<ExitCode> {
    let cli = args::Cli::parse();
    match cli.command {
        args::Command::Info(a) => info::run(&a),
        args::Command::Mesh(a) => mesh::run(&a),
        args::Command::Compare(a) => compare::run(&a),
        args::Command::Stream(c) => stream::run(&c),
    }
}
