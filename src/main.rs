//! `cullgraph`: render scenes headlessly, list devices (and, later, check graphs and benchmark).

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
