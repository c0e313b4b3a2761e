//! The viewer's pages and scripts, embedded at build time by `build.rs`
//! (from `viewer/`, built by esbuild), served from memory: a request can only
//! name a file of this table, never one on disk.

/// One embedded file.
#[derive(Debug)]
pub struct Embedded {
    /// Path below the site root, with `/` (`index.html`, `assets/main-HASH.js`).
    pub path: &'static str,
    /// The file's bytes.
    pub bytes: &'static [u8],
    /// FNV-1a 64 of the bytes, hex: the strong ETag.
    pub etag: &'static str,
}

include!(concat!(env!("OUT_DIR"), "/assets.rs"));

/// The embedded file at `path` (no leading `/`).
pub fn find(path: &str) -> Option<&'static Embedded> {
    FILES
        .binary_search_by(|e| e.path.cmp(path))
        .ok()
        .and_then(|i| FILES.get(i))
}

/// The `Content-Type` of an embedded file, from its extension.
pub fn mime(path: &str) -> &'static str {
    let ext = path.rsplit_once('.').map_or("", |(_, e)| e);
    match ext {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "json" => "application/json",
        "wasm" => "application/wasm",
        "png" => "image/png",
        "jpg" | "jpeg" => "image/jpeg",
        "svg" => "image/svg+xml",
        "gif" => "image/gif",
        "xml" => "application/xml",
        "ktx2" => "image/ktx2",
        "glb" => "model/gltf-binary",
        _ => "application/octet-stream",
    }
}

/// The `Cache-Control` of an embedded file: pages are revalidated, the
/// viewer's content-hashed bundles (`assets/`) never change, CesiumJS's files
/// keep their names across builds and are kept a day.
pub fn cache_control(path: &str) -> &'static str {
    if path.ends_with(".html") {
        "no-cache"
    } else if path.starts_with("assets/") {
        "public, max-age=31536000, immutable"
    } else {
        "public, max-age=86400"
    }
}
