//! The `flightid` binary: parses arguments and calls into the library (see `flightid::cli`).

fn main() {
    std::process::exit(flightid_cli::main());
}

mod flightid_cli {
    pub fn main() -> i32 {
        flightid::cli::main()
    }
}
