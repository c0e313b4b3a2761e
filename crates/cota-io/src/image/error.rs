//! The errors of the imagery reader ([`super`]): each names the file, says
//! what was expected and what was found.

use std::path::PathBuf;

/// A failure to read an image or to place it on a DEM.
#[derive(Debug, thiserror::Error)]
#[error("{}: {kind}", path.display())]
pub struct ImageError {
    /// The image file.
    pub path: PathBuf,
    /// What went wrong.
    pub kind: ImageErrorKind,
}

impl ImageError {
    /// Wraps `kind` with the image's path.
    pub fn new(path: &std::path::Path, kind: ImageErrorKind) -> Self {
        ImageError {
            path: path.to_path_buf(),
            kind,
        }
    }
}

/// What went wrong with an image.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImageErrorKind {
    /// The OS refused (missing file, permission, ...).
    #[error("cannot read the file: {0}")]
    Io(#[from] std::io::Error),
    /// The content is not a GeoTIFF, PNG or JPEG.
    #[error("expected an image (GeoTIFF, PNG or JPEG), found {found}")]
    UnknownFormat {
        /// What the first bytes look like.
        found: String,
    },
    /// The GeoTIFF reader refused a band (its own message).
    #[error(transparent)]
    Tiff(#[from] crate::error::ReadErrorKind),
    /// The PNG or JPEG decoder refused the content.
    #[error("expected a well-formed {format}, found {detail}")]
    Decode {
        /// PNG or JPEG.
        format: &'static str,
        /// The decoder's message.
        detail: String,
    },
    /// More bands asked for than the image has.
    #[error("expected an image with band{} {asked} (--bands), found {found} band{}", if asked.contains(',') { "s" } else { "" }, if *found == 1 { "" } else { "s" })]
    MissingBand {
        /// The bands asked for, e.g. `3,2,1`.
        asked: String,
        /// Bands in the image.
        found: u16,
    },
    /// A band list that is not 1 or 3 bands numbered from 1.
    #[error("expected 1 or 3 band numbers from 1 (e.g. 3,2,1), found {0}")]
    BadBands(String),
    /// The image is larger than cota reads.
    #[error("expected at most {max} pixels, found {width}x{height}")]
    TooLarge {
        /// Width.
        width: u64,
        /// Height.
        height: u64,
        /// The limit.
        max: u64,
    },
    /// A world file that cannot be used.
    #[error("world file {}: expected {expected}, found {found}", file.display())]
    WorldFile {
        /// The world file.
        file: PathBuf,
        /// What a usable world file holds.
        expected: &'static str,
        /// What it holds.
        found: String,
    },
    /// The image's CRS is not the DEM's.
    #[error("expected the DEM's CRS ({dem}), found the image in {image}: {why}")]
    CrsMismatch {
        /// The DEM's CRS.
        dem: String,
        /// The image's CRS.
        image: String,
        /// Why they do not count as the same (and what to do).
        why: String,
    },
    /// The image does not cover the DEM, or its placement is unusable.
    #[error(transparent)]
    Placement(#[from] cota_core::texture::TextureError),
}
