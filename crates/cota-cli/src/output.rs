//! Checks on output paths made before any long work.

use std::path::Path;

use cota_io::export::MeshFormat;

/// Fails early, before any long work, on output paths that cannot be written.
pub fn check_output(out: &Path, base_m: Option<f64>) -> anyhow::Result<MeshFormat> {
    let format = MeshFormat::from_path(out)?;
    if base_m.is_some() && format != MeshFormat::Stl {
        anyhow::bail!(
            "{}: --base-m makes a closed solid for 3D printing and applies to .stl output only, found .{format}",
            out.display()
        );
    }
    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        anyhow::bail!(
            "cannot write {}: expected an existing directory {}, found none",
            out.display(),
            dir.display()
        );
    }
    if out.is_dir() {
        anyhow::bail!("cannot write {}: it is a directory", out.display());
    }
    Ok(format)
}
