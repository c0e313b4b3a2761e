//! Format detection: what the first bytes of a file look like ([`sniff`]),
//! and how to describe content that matches no format in an error message
//! ([`describe_bytes`], [`name_hint`]).

use std::path::Path;

/// What the first bytes of a file look like.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Sniffed {
    Gzip,
    Zip,
    Tiff,
    Png,
    WebP,
    Pmtiles,
    Npy,
    UsgsDem,
    Ascii,
    Unknown,
}

/// Keys that may open an ESRI ASCII grid header (lower case).
const ASCII_HEADER_KEYS: [&str; 6] = [
    "ncols",
    "nrows",
    "xllcorner",
    "xllcenter",
    "yllcorner",
    "yllcenter",
];

/// Classifies content by its magic bytes and, for text, its first keyword.
pub(crate) fn sniff(bytes: &[u8]) -> Sniffed {
    if bytes.starts_with(b"\x1f\x8b") {
        Sniffed::Gzip
    } else if bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06") {
        Sniffed::Zip
    } else if bytes.starts_with(b"II*\0")
        || bytes.starts_with(b"MM\0*")
        || bytes.starts_with(b"II+\0")
        || bytes.starts_with(b"MM\0+")
    {
        Sniffed::Tiff
    } else if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Sniffed::Png
    } else if super::webp::is_webp(bytes) {
        Sniffed::WebP
    } else if bytes.starts_with(b"PMTiles") {
        Sniffed::Pmtiles
    } else if bytes.starts_with(b"\x93NUMPY") {
        Sniffed::Npy
    } else if super::usgs_dem::is_usgs_dem(bytes) {
        Sniffed::UsgsDem
    } else {
        let head = &bytes[..bytes.len().min(64)];
        let head = head.strip_prefix(b"\xef\xbb\xbf").unwrap_or(head); // UTF-8 BOM
        let text = String::from_utf8_lossy(head).to_ascii_lowercase();
        let t = text.trim_start();
        if ASCII_HEADER_KEYS.iter().any(|k| t.starts_with(k)) {
            Sniffed::Ascii
        } else {
            Sniffed::Unknown
        }
    }
}

/// Describes unrecognised content for an error message.
pub(crate) fn describe_bytes(bytes: &[u8]) -> String {
    let n = bytes.len().min(8);
    let printable = bytes[..n]
        .iter()
        .all(|b| b.is_ascii_graphic() || *b == b' ' || *b == b'\n' || *b == b'\r' || *b == b'\t');
    if printable {
        let s = String::from_utf8_lossy(&bytes[..bytes.len().min(24)]);
        format!(
            "text starting {:?} ({} bytes)",
            s.lines().next().unwrap_or(""),
            bytes.len()
        )
    } else {
        let hex: Vec<String> = bytes[..n].iter().map(|b| format!("{b:02x}")).collect();
        format!("bytes {} ({} bytes)", hex.join(" "), bytes.len())
    }
}

/// For unrecognised content, what the file's extension promised and lacks
/// (e.g. ", not a PNG despite the .png name: no PNG signature 89 50 4e 47");
/// empty when the extension says nothing.
pub(crate) fn name_hint(path: &Path) -> String {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let lacks = match ext.as_str() {
        "png" => "a PNG: no PNG signature 89 50 4e 47 0d 0a 1a 0a",
        "tif" | "tiff" => "a TIFF: no TIFF header II*\\0 or MM\\0*",
        "asc" => "an ESRI ASCII grid: no header key such as ncols",
        "zip" | "npz" => "a ZIP archive: no PK\\x03\\x04 signature",
        "webp" => "a WebP image: no RIFF....WEBP header",
        "npy" => "a NumPy array: no \\x93NUMPY signature",
        "pmtiles" => "a PMTiles archive: no PMTiles signature",
        "dem" => "a USGS ASCII DEM: no type A record (1024 bytes, level, pattern and unit codes)",
        // No extension (standard input, `<stdin>`): only the content can
        // tell, and a raw .hgt has no magic.
        "" => {
            return ", and no extension to go by (a raw .hgt is known without its name only as a \
                    1201² or 3601² tile: name the file N45E006.hgt)"
                .to_string()
        }
        _ => return String::new(),
    };
    format!(", not {lacks} despite the .{ext} name")
}
