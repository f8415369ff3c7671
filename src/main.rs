//! `mtsim`: the command line. All the work is in the library; see `mtsim::cli`.

fn main() {
    std::process::exit(mtsim::cli::main());
}
