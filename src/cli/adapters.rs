//! `meshtrace adapters`: the Vulkan adapters, for `--adapter`.

use super::out;
use anyhow::{Result, bail};
use meshtrace::render::gpu::{self, GpuError};

pub fn adapters() -> Result<()> {
    let list = gpu::list_adapters();
    if list.is_empty() {
        bail!("{}", GpuError::NoAdapter);
    }
    for a in list {
        out!(
            "{}  {}  ({}, {}, {}; {})",
            a.index,
            a.name,
            a.backend,
            a.device_type,
            a.driver,
            if a.ray_query {
                "ray queries"
            } else {
                "no ray queries"
            }
        );
    }
    Ok(())
}
