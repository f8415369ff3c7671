//! `mtsim man`: the man pages (roff), rendered by clap_mangen from the command line's
//! definition, so they list exactly the options `--help` lists.

use std::path::Path;

use super::print_stdout;
use crate::error::{Error, Result};
use crate::report::write_atomic;

/// The command line `cli` as the pages describe it: built (so each subcommand's page is
/// titled `mtsim-NAME`) and without clap's `help` subcommand, which has no page of its own.
fn built(cli: clap::Command) -> clap::Command {
    let mut cmd = cli.disable_help_subcommand(true);
    cmd.build();
    cmd
}

fn render(cmd: clap::Command) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    clap_mangen::Man::new(cmd)
        .render(&mut out)
        .map_err(|source| Error::Write {
            path: "<man page>".into(),
            source,
        })?;
    Ok(out)
}

/// The pages of the command line `cli`. Without `dir`: `mtsim.1` on standard output. With `dir`: `dir/mtsim.1` and one
/// `dir/mtsim-NAME.1` for every subcommand its SUBCOMMANDS section names (each file
/// written atomically; `dir` created if missing). Returns the exit code.
pub fn run(cli: clap::Command, dir: Option<&Path>) -> Result<i32> {
    let cmd = built(cli);
    let Some(dir) = dir else {
        print_stdout(&String::from_utf8_lossy(&render(cmd)?));
        return Ok(0);
    };
    std::fs::create_dir_all(dir).map_err(|source| Error::Write {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut written = Vec::new();
    for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
        let name = format!("mtsim-{}.1", sub.get_name());
        write_atomic(&dir.join(&name), &render(sub.clone())?)?;
        written.push(name);
    }
    write_atomic(&dir.join("mtsim.1"), &render(cmd)?)?;
    super::note(&format!(
        "wrote mtsim.1 and {} subcommand pages ({}) in {}",
        written.len(),
        written.join(", "),
        dir.display()
    ));
    Ok(0)
}
