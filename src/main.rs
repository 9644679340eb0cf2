//! `cullgraph`: render scenes headlessly, list devices (and, later, check graphs and benchmark).

mod cli;

fn main() -> std::process::ExitCode {
    // Tracy's scopes need its client running before the first one opens.
    #[cfg(feature = "profile-with-tracy")]
    let _tracy = profiling::tracy_client::Client::start();
    cli::main()
}
