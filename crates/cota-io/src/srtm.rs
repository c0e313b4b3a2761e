//! Reader stub: being written.
use std::path::Path;

use crate::error::ReadErrorKind;
use crate::read::{Dem, ReadOptions};

/// Decodes the content of one file of this format. `path` supplies the name.
pub(crate) fn decode(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    let _ = (bytes, path, opts);
    Err(ReadErrorKind::Unsupported {
        what: "format".into(),
        detail: "srtm reader not written yet".into(),
    })
}

/// True when `bytes` could be a raw `.hgt` (n×n big-endian i16) or the name says `.hgt`.
pub(crate) fn looks_like_hgt(bytes: &[u8], path: &Path) -> bool {
    let _ = bytes;
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("hgt"))
}
