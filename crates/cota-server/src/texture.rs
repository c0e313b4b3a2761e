//! [`Textures`]: an image draped on the terrain in the viewer, prepared at
//! start (`cota serve --texture`): the image resampled onto the texture
//! raster spanning the DEM's samples (`cota_io::image::drape_file`) at
//! `/texture.png`, and optionally the texture level of paper 004's chosen
//! (mesh, texture) pair at `/texture-pair.png`. `/meta.json` describes both
//! under `texture`. One texture each, not a streamed quadtree: the stream
//! carries heights only, and the texture's size is bounded at start.

use axum::body::Bytes;
use cota_core::texture::RgbImage;
use serde::Serialize;

use crate::error::Result;
use crate::tiles::etag_of;

/// `/texture.png`.
pub const TEXTURE_URL: &str = "/texture.png";
/// `/texture-pair.png`.
pub const PAIR_URL: &str = "/texture-pair.png";

/// What `/meta.json` says of one texture.
#[derive(Debug, Clone, Serialize)]
pub struct TextureMeta {
    /// Where it is served.
    pub url: String,
    /// Width, texels (west to east: the DEM's first to last sample column).
    pub width: usize,
    /// Height, texels (north to south: the DEM's first to last sample row).
    pub height: usize,
    /// Bytes of the PNG.
    pub bytes: usize,
    /// What it is (image, bands, CRS rule; or the pair chosen), as the
    /// command that made it says.
    pub about: serde_json::Value,
}

/// One PNG texture.
#[derive(Debug, Clone)]
pub struct TextureLevel {
    png: Bytes,
    etag: String,
    meta: TextureMeta,
}

impl TextureLevel {
    /// `image`, encoded as PNG, served at `url`.
    ///
    /// # Errors
    /// [`crate::ServeError::Texture`] when the PNG cannot be encoded.
    pub fn from_rgb(image: &RgbImage, url: &str, about: serde_json::Value) -> Result<Self> {
        let png = cota_io::export::encode_png(image)?;
        Ok(Self::from_png(
            png,
            [image.width(), image.height()],
            url,
            about,
        ))
    }

    /// A PNG already encoded, of `size` (width, height) texels.
    pub fn from_png(png: Vec<u8>, size: [usize; 2], url: &str, about: serde_json::Value) -> Self {
        let meta = TextureMeta {
            url: url.into(),
            width: size[0],
            height: size[1],
            bytes: png.len(),
            about,
        };
        TextureLevel {
            etag: etag_of(&png),
            png: Bytes::from(png),
            meta,
        }
    }

    /// The PNG.
    pub fn png(&self) -> &Bytes {
        &self.png
    }

    /// Its strong ETag, quoted.
    pub fn etag(&self) -> &str {
        &self.etag
    }

    /// Its description.
    pub fn meta(&self) -> &TextureMeta {
        &self.meta
    }
}

/// The textures the viewer may drape.
#[derive(Debug, Clone)]
pub struct Textures {
    /// The whole image (`/texture.png`).
    pub image: TextureLevel,
    /// Paper 004's chosen texture level (`/texture-pair.png`), if asked for.
    pub pair: Option<TextureLevel>,
}

/// What `/meta.json` says under `texture`.
#[derive(Debug, Clone, Serialize)]
pub struct TexturesMeta {
    /// The whole image.
    pub image: TextureMeta,
    /// The pair's texture level.
    pub pair: Option<TextureMeta>,
}

impl Textures {
    /// The description served in `/meta.json`.
    pub fn meta(&self) -> TexturesMeta {
        TexturesMeta {
            image: self.image.meta.clone(),
            pair: self.pair.as_ref().map(|p| p.meta.clone()),
        }
    }
}
