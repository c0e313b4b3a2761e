//! Reader stub: being written.
use std::path::Path;

use crate::error::ReadErrorKind;
use crate::read::{Dem, ReadOptions};

/// Decodes the content of one file of this format. `path` supplies the name.
pub(crate) fn decode(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    let _ = (bytes, path, opts);
    Err(ReadErrorKind::Unsupported {
        what: "format".into(),
        detail: "png reader not written yet".into(),
    })
}
