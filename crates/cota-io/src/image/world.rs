//! World files (`.pgw`, `.jgw`, `.tfw`, `.wld`, and the `…w` forms such as
//! `.pngw`): six lines, the ESRI convention — pixel width `A`, rotation `D`,
//! rotation `B`, pixel height `E` (negative for north-up), then the x `C`
//! and y `F` of the *centre* of the top-left pixel. Rotated world files
//! (`B` or `D` not 0) are refused: cota drapes north-up images only. A world
//! file carries no CRS.

use std::path::{Path, PathBuf};

use cota_core::texture::ImagePlacement;

use super::error::ImageErrorKind;

/// The world file beside `image`, if any: the same stem with the image
/// format's extensions, then `.wld`.
pub(super) fn find(image: &Path) -> Option<PathBuf> {
    let ext = image.extension()?.to_string_lossy().to_ascii_lowercase();
    let exts: &[&str] = match ext.as_str() {
        "png" => &["pgw", "pngw", "PGW"],
        "jpg" | "jpeg" => &["jgw", "jpgw", "jpegw", "JGW"],
        "tif" | "tiff" => &["tfw", "tifw", "TFW"],
        _ => &[],
    };
    exts.iter()
        .chain(&["wld"])
        .map(|e| image.with_extension(e))
        .find(|p| p.is_file())
}

/// Largest world file read (six numbers take well under a kilobyte).
const MAX_WORLD_FILE_BYTES: u64 = 64 << 10;

/// Reads and parses the world file `file`.
pub(super) fn read(file: &Path) -> Result<ImagePlacement, ImageErrorKind> {
    let bytes = crate::limits::read_file_capped(file, MAX_WORLD_FILE_BYTES)?;
    let text = String::from_utf8(bytes)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))?;
    parse(&text).map_err(|(expected, found)| ImageErrorKind::WorldFile {
        file: file.to_path_buf(),
        expected,
        found,
    })
}

/// The placement six world-file numbers give.
fn parse(text: &str) -> Result<ImagePlacement, (&'static str, String)> {
    let v: Vec<f64> = text
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .map_err(|e| ("six numbers", format!("a word that is not a number ({e})")))?;
    let &[a, d, b, e, c, f] = v.as_slice() else {
        return Err(("six numbers", format!("{}", v.len())));
    };
    if d != 0.0 || b != 0.0 {
        return Err((
            "a north-up image (rotation terms 0)",
            format!("rotation terms {d} and {b}"),
        ));
    }
    if ![a, e, c, f].iter().all(|x| x.is_finite()) || a == 0.0 || e == 0.0 {
        return Err((
            "finite numbers and non-zero pixel sizes",
            format!("pixel {a} x {e} at ({c}, {f})"),
        ));
    }
    Ok(ImagePlacement {
        origin_x: c - a / 2.0,
        origin_y: f - e / 2.0,
        pixel_x: a,
        pixel_y: e,
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used, reason = "tests")]
mod tests {
    use super::*;

    #[test]
    fn parses_the_esri_convention() {
        let p = parse("28.5\n0\n0\n-28.5\n288790.5\n9120746.5\n").unwrap();
        assert_eq!((p.origin_x, p.origin_y), (288776.25, 9120760.75));
        assert_eq!((p.pixel_x, p.pixel_y), (28.5, -28.5));
        assert!(parse("1 0 0 -1 5").is_err());
        assert!(parse("1 0.1 0 -1 5 6").unwrap_err().0.contains("north-up"));
        assert!(parse("1 0 0 x 5 6").is_err());
        assert!(parse("0 0 0 -1 5 6").is_err());
    }
}
