//! `lucent render`.

use crate::cli::RenderArgs;

pub fn run(_args: &RenderArgs) -> anyhow::Result<()> {
    anyhow::bail!("render: not implemented yet")
}
