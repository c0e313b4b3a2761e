//! Output paths: checks made before any long work, and the one way every
//! command writes a file (atomically, `--force` for read-only targets) or
//! standard output (`-o -`).

use std::io::{IsTerminal, Write};
use std::path::Path;

use anyhow::Context;
use cota_io::export::{ExportError, MeshFormat};

use crate::args::MeshFormatArg;
use crate::input::is_dash;

/// The format of mesh output `out`: `--format` when given (a file's
/// extension must then agree), else the extension. Standard output (`-`)
/// needs `--format`.
pub fn format_of(out: &Path, flag: Option<MeshFormatArg>) -> anyhow::Result<MeshFormat> {
    let flag = flag.map(MeshFormatArg::format);
    if is_dash(out) {
        return flag.ok_or_else(|| {
            anyhow::anyhow!(
                "-o -: expected --format obj, ply, stl or glb (standard output has no extension)"
            )
        });
    }
    let ext = MeshFormat::from_path(out)?;
    match flag {
        Some(f) if f != ext => anyhow::bail!(
            "{}: --format {f} disagrees with the extension .{ext}",
            out.display()
        ),
        _ => Ok(ext),
    }
}

/// Fails early, before any long work, on output paths that cannot be
/// written; returns the format. Standard output (`-`) takes any format but
/// a binary one on a terminal.
pub fn check_output(
    out: &Path,
    flag: Option<MeshFormatArg>,
    base_m: Option<f64>,
) -> anyhow::Result<MeshFormat> {
    let format = format_of(out, flag)?;
    if base_m.is_some() && format != MeshFormat::Stl {
        anyhow::bail!(
            "{}: --base-m and --base-mm make a closed solid for 3D printing and apply to .stl output only, found .{format}",
            out.display()
        );
    }
    if is_dash(out) {
        if format != MeshFormat::Obj && std::io::stdout().is_terminal() {
            anyhow::bail!(
                "-o -: refusing to write binary .{format} to a terminal; redirect standard output to a file or a pipe"
            );
        }
        return Ok(format);
    }
    check_file_path(out)?;
    Ok(format)
}

/// Fails early on a file path that cannot be written: no such directory,
/// a directory in its place, or a directory where no file can be made.
pub fn check_file_path(out: &Path) -> anyhow::Result<()> {
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
    probe_dir(out, dir)
}

/// Fails early unless a file can be made in `dir` (the directory `out` goes
/// to): a read-only directory, `/proc` or a full disk would otherwise fail
/// only when the work is done. Creates and removes an empty file there.
pub fn probe_dir(out: &Path, dir: &Path) -> anyhow::Result<()> {
    let probe = dir.join(format!(".cota-probe-{}", std::process::id()));
    let made = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe);
    match made {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => anyhow::bail!(
            "cannot write {}: cannot create a file in {}: {e}",
            out.display(),
            dir.display()
        ),
    }
}

/// Fails early on an output directory (`cota tiles -o DIR`) that cannot be
/// written: an existing file that is not a directory, or no writable
/// directory to make it in. `archive`: `out` is a file (`.mbtiles`) instead,
/// whose directories are made as a directory output's are.
pub fn check_output_dir(out: &Path, archive: bool) -> anyhow::Result<()> {
    if archive && out.is_dir() {
        anyhow::bail!("cannot write {}: it is a directory", out.display());
    }
    if !archive && out.exists() && !out.is_dir() {
        anyhow::bail!(
            "cannot write {}: expected a directory, found a file",
            out.display()
        );
    }
    // The nearest directory that exists: where the output (or the
    // directories made for it) goes.
    let mut dir = match out.parent() {
        Some(p) if archive && !p.as_os_str().is_empty() => p,
        _ if archive => Path::new("."),
        _ => out,
    };
    while !dir.exists() {
        match dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => dir = p,
            _ => return probe_dir(out, Path::new(".")),
        }
    }
    if !dir.is_dir() {
        anyhow::bail!(
            "cannot write {}: {} is not a directory",
            out.display(),
            dir.display()
        );
    }
    probe_dir(out, dir)
}

/// Writes what `encode` writes to `out`: atomically to a file (a read-only
/// file refused unless `force`), or to standard output for `-` (no atomic
/// rename there: an error part-way leaves what was already sent).
pub fn write_with<F>(out: &Path, force: bool, encode: F) -> anyhow::Result<()>
where
    F: FnOnce(&mut (dyn Write + Send)) -> Result<(), ExportError>,
{
    if !is_dash(out) {
        cota_io::export::write_atomically_forced(out, force, encode)?;
        return Ok(());
    }
    let mut w = std::io::BufWriter::with_capacity(1 << 20, std::io::stdout());
    let written = encode(&mut w).and_then(|()| w.flush().map_err(ExportError::Io));
    match written {
        // The reader went away (`cota mesh -o - ... | head`): not an error
        // of cota's; stop quietly, as other Unix tools do.
        Err(ExportError::Io(e)) if e.kind() == std::io::ErrorKind::BrokenPipe => {
            std::process::exit(0)
        }
        r => r.context("-: writing to standard output"),
    }
}

/// Prints a report: to stdout, or to stderr when the output itself goes to
/// stdout (`-o -`). A text report (`json` false) is not printed with
/// `--quiet`.
pub fn print_report(out: Option<&Path>, text: &str, json: bool) {
    if !json && crate::progress::quiet() {
        return;
    }
    if out.is_some_and(is_dash) {
        eprint!("{text}");
    } else {
        print!("{text}");
    }
}
