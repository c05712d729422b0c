//! `lucent view`: the interactive viewer.

use crate::cli::ViewArgs;

pub fn run(_args: &ViewArgs) -> anyhow::Result<()> {
    anyhow::bail!("view: not implemented yet")
}
