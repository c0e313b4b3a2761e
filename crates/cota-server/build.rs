//! Embeds the browser viewer (`viewer/`) into the crate.
//!
//! Where the built pages come from, first match wins:
//! 1. `COTA_VIEWER_DIST=DIR`: a directory built elsewhere (`npm run build`).
//! 2. `viewer/node_modules` installed (`npm ci`) and `node` on the path: this
//!    script runs `node viewer/build.mjs --outdir $OUT_DIR/viewer-dist` (esbuild,
//!    offline, about a second) and embeds the result.
//! 3. `viewer/dist/`, left by `npm run build`.
//! 4. Otherwise a page that says how to build the viewer (the server still
//!    serves the stream, the tiles and `/health`; `/health` reports
//!    `"viewer": "missing"`).
//!
//! The bundle holds third-party code (three.js, CesiumJS), so it is never
//! committed: it is rebuilt from the committed `package-lock.json`.

use std::env;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap_or_default());
    let out = PathBuf::from(env::var("OUT_DIR").unwrap_or_default());
    let viewer = manifest.join("viewer");
    println!("cargo:rerun-if-env-changed=COTA_VIEWER_DIST");
    for p in [
        "src",
        "build.mjs",
        "package.json",
        "package-lock.json",
        "node_modules/.package-lock.json",
        "dist/index.html",
    ] {
        // A path that does not exist would make cargo rerun this script on
        // every build: watch only what is there.
        if viewer.join(p).exists() {
            println!("cargo:rerun-if-changed=viewer/{p}");
        }
    }
    let (dir, how) = locate(&viewer, &out);
    let code = match &dir {
        Some(d) => assets_code(d, how),
        None => {
            // Notice a later `npm ci` or `npm run build` (the folder is small
            // without node_modules).
            println!("cargo:rerun-if-changed=viewer");
            fallback_code(&out)
        }
    };
    if let Err(e) = fs::write(out.join("assets.rs"), code) {
        println!("cargo:warning=cannot write assets.rs: {e}");
    }
}

/// The directory of built pages and how it was obtained.
fn locate(viewer: &Path, out: &Path) -> (Option<PathBuf>, &'static str) {
    if let Ok(d) = env::var("COTA_VIEWER_DIST") {
        let d = PathBuf::from(d);
        if d.join("index.html").is_file() {
            return (Some(d), "COTA_VIEWER_DIST");
        }
        println!(
            "cargo:warning=COTA_VIEWER_DIST={} has no index.html; ignored",
            d.display()
        );
    }
    if viewer.join("node_modules/.package-lock.json").is_file() {
        let dist = out.join("viewer-dist");
        let status = Command::new("node")
            .arg("build.mjs")
            .arg("--outdir")
            .arg(&dist)
            .current_dir(viewer)
            .status();
        match status {
            Ok(s) if s.success() && dist.join("index.html").is_file() => {
                return (Some(dist), "built by build.rs (node build.mjs)");
            }
            Ok(s) => println!("cargo:warning=viewer build (node build.mjs) failed: {s}"),
            Err(e) => println!("cargo:warning=viewer build: cannot run node: {e}"),
        }
    }
    let dist = viewer.join("dist");
    if dist.join("index.html").is_file() {
        return (Some(dist), "viewer/dist (npm run build)");
    }
    println!(
        "cargo:warning=cota-server: the viewer is not built (run `npm ci` in \
         crates/cota-server/viewer); / and /cesium will say so"
    );
    (None, "missing")
}

/// Every file under `dir`, sorted, as paths relative to it with `/`.
fn files(dir: &Path) -> Vec<(String, PathBuf)> {
    let mut v = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = fs::read_dir(&d) else { continue };
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if let Ok(rel) = p.strip_prefix(dir) {
                let rel: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                v.push((rel.join("/"), p));
            }
        }
    }
    v.sort();
    v
}

/// FNV-1a, 64 bits: the ETag of an embedded file.
fn fnv64(b: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &x in b {
        h ^= x as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

fn assets_code(dir: &Path, how: &str) -> String {
    let mut s = String::new();
    s.push_str(&format!(
        "/// Where the embedded viewer came from.\npub const SOURCE: &str = {how:?};\n\
         /// True when the viewer was built.\npub const BUILT: bool = true;\n\
         /// The embedded files.\npub static FILES: &[Embedded] = &[\n"
    ));
    for (rel, path) in files(dir) {
        let Ok(bytes) = fs::read(&path) else { continue };
        let abs = path.canonicalize().unwrap_or(path);
        s.push_str(&format!(
            "    Embedded {{ path: {rel:?}, bytes: include_bytes!({:?}), etag: \"{:016x}\" }},\n",
            abs.to_string_lossy(),
            fnv64(&bytes)
        ));
    }
    s.push_str("];\n");
    s
}

/// The fallback page for `/` and `/cesium` (sorted by path: `assets::find`
/// searches binary).
fn fallback_code(out: &Path) -> String {
    let page = "<!doctype html><html><head><meta charset=\"utf-8\"><title>cota viewer not built</title>\
        </head><body data-cota-page=\"missing\"><h1>cota: the viewer is not built</h1>\
        <p>This binary was built without the viewer's JavaScript bundle. Build it with \
        <code>cd crates/cota-server/viewer &amp;&amp; npm ci</code> (node and npm needed), then rebuild \
        (<code>cargo build --release -p cota-cli</code>). The stream (<code>/stream</code>), the tiles \
        (<code>/layer.json</code>) and <code>/health</code> are served all the same.</p></body></html>\n";
    let path = out.join("viewer-missing.html");
    if let Err(e) = fs::write(&path, page) {
        println!("cargo:warning=cannot write the fallback page: {e}");
    }
    let etag = fnv64(page.as_bytes());
    let p = path.to_string_lossy();
    format!(
        "/// Where the embedded viewer came from.\npub const SOURCE: &str = \"missing\";\n\
         /// True when the viewer was built.\npub const BUILT: bool = false;\n\
         /// The embedded files.\npub static FILES: &[Embedded] = &[\n\
         \x20   Embedded {{ path: \"cesium.html\", bytes: include_bytes!({p:?}), etag: \"{etag:016x}\" }},\n\
         \x20   Embedded {{ path: \"index.html\", bytes: include_bytes!({p:?}), etag: \"{etag:016x}\" }},\n\
         ];\n"
    )
}
