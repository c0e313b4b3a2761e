//! `cota pair`: paper 004's best (mesh, texture) pair under a byte budget,
//! written as a textured GLB; and `cota mesh --texture`, which drapes the
//! full image on any mesh.
//!
//! Flow: read the DEM (voids filled) and the image (bands), place the image
//! on the DEM (same CRS, `cota_io::image::crs`), resample it bilinearly onto
//! the texture raster spanning the DEM's samples; the texture list is the
//! texture quadtree at `--texture-tolerances`, each leaf flat colour,
//! rendered at the raster's resolution and encoded as PNG; the mesh list is
//! the bitree and the restricted quadtree at `--mesh-tolerances-m`. The
//! byte model is the GLB's: `C(M)` = the mesh's views, `C(T)` = the PNG,
//! and the file is `C(M) + C(T)` plus a frame (header, chunk headers, JSON)
//! of at most [`FRAME_RESERVE_BYTES`], so pairs are chosen within
//! `budget − FRAME_RESERVE_BYTES` and the file is never over the budget.

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use cota_core::pair::{
    choose, mesh_list_with_progress, Candidate, Choice, MeshCandidate, MeshListOptions, PairOptions,
};
use cota_core::quadtree::QuadOptions;
use cota_core::texture::{DrapeOptions, RgbImage, TextureQuadtree};
use cota_core::{HeightGrid, HierarchyKind, Mesh, Mesher};
use cota_io::export::{encode_png, textured_mesh_bytes, write_glb_textured, ExportOptions};
use cota_io::image::{drape_file, Bands, DrapeFileOptions, ImageOptions};
use serde_json::{json, Value};

use crate::args::{
    Hierarchies, ImageArgs, InputArgs, MeshFormatArg, PairArgs, Pick, TextureArgs, Voids,
};
use crate::input::is_dash;

/// Bytes kept for the GLB's frame (12-byte header, two chunk headers, the
/// JSON padded to 4): the JSON of a textured GLB is about 1.2 KB.
pub const FRAME_RESERVE_BYTES: u64 = 4096;

/// One texture of the list: its tolerance, leaves, D(T) and the PNG.
struct TextureCandidate {
    tolerance: f64,
    leaves: usize,
    quadtree_bytes: u64,
    distortion: u64,
    png: Vec<u8>,
}

impl TextureCandidate {
    fn candidate(&self) -> Candidate {
        Candidate {
            bytes: pad4(self.png.len() as u64),
            distortion: self.distortion as f64,
            elements: self.leaves as u64,
        }
    }
}

fn pad4(n: u64) -> u64 {
    n.div_ceil(4) * 4
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The DEM, read with the reading flags as every command reads its input
/// (`-`: standard input; the window of `--crop` or `--bbox`), voids filled
/// harmonically, and the image draped on it (the texture raster).
fn read_pair(a: &PairArgs) -> anyhow::Result<(HeightGrid, RgbImage, Value)> {
    let input = crate::input::load(&InputArgs {
        files: vec![a.dem.clone()],
        read: a.read.clone(),
    })?;
    let mut grid = input.grid;
    crate::input::fill(&mut grid, Voids::Fill)?;
    let _spinner = crate::progress::spinner("draping");
    let (texture, about) = drape_image(&grid, &a.image, &a.image_args)?;
    Ok((grid, texture, about))
}

/// The `--bands` of `a`, parsed.
pub fn bands_of(a: &ImageArgs) -> anyhow::Result<Option<Bands>> {
    match &a.bands {
        Some(b) => Ok(Some(
            Bands::parse(b).map_err(|e| anyhow::anyhow!("--bands: {e}"))?,
        )),
        None => Ok(None),
    }
}

/// Reads `image`, places it on `grid` and resamples it onto the texture
/// raster, at most `max_side` texels a side
/// ([`cota_io::image::drape_file`]); and what was done, as JSON.
pub fn drape_image_within(
    grid: &HeightGrid,
    image: &Path,
    a: &ImageArgs,
    max_side: usize,
) -> anyhow::Result<(RgbImage, Value)> {
    let opts = DrapeFileOptions::DEFAULT
        .with_image(ImageOptions::DEFAULT.with_bands(bands_of(a)?))
        .with_assume_same_crs(a.assume_same_crs)
        .with_drape(DrapeOptions::DEFAULT.with_max_side_texels(max_side));
    let d = drape_file(image, grid, &opts)?;
    let about = json!({
        "image": image.display().to_string(),
        "format": d.format,
        "image_size": d.image_size,
        "bands": d.bands.text(),
        "band_count": d.band_count,
        "image_crs": d.image_crs.to_string(),
        "dem_crs": grid.georef().crs.to_string(),
        "placement": d.placement_source,
        "crs_rule": d.rule,
        "resampling": "bilinear per channel onto the texture raster spanning the DEM's samples",
        "texture_size": [d.texture.width(), d.texture.height()],
    });
    Ok((d.texture, about))
}

/// [`drape_image_within`] at the default bound ([`DrapeOptions::DEFAULT`]).
pub fn drape_image(
    grid: &HeightGrid,
    image: &Path,
    a: &ImageArgs,
) -> anyhow::Result<(RgbImage, Value)> {
    drape_image_within(grid, image, a, DrapeOptions::DEFAULT.max_side_texels)
}

/// The texture list: the quadtree at each tolerance, rendered and encoded.
fn texture_list(texture: &RgbImage, tolerances: &[f64]) -> anyhow::Result<Vec<TextureCandidate>> {
    // The tree's build counts as one tolerance.
    let pb = crate::progress::bar(tolerances.len() as u64 + 1, "listing textures");
    let tree = TextureQuadtree::build(texture);
    pb.set_position(1);
    let mut out: Vec<TextureCandidate> = Vec::new();
    for (k, &tol) in tolerances.iter().enumerate() {
        pb.set_position(k as u64 + 1);
        if !(tol >= 0.0 && tol.is_finite()) {
            anyhow::bail!("--texture-tolerances: expected 0 or more levels, found {tol}");
        }
        let x = tree.extract(tol);
        if out
            .iter()
            .any(|t| t.leaves == x.leaves.len() && t.distortion == x.distortion)
        {
            continue;
        }
        out.push(TextureCandidate {
            tolerance: tol,
            leaves: x.leaves.len(),
            quadtree_bytes: x.bytes(),
            distortion: x.distortion,
            png: encode_png(&x.render())?,
        });
    }
    pb.set_position(tolerances.len() as u64 + 1);
    Ok(out)
}

/// The mesh list of the flags.
fn meshes(a: &PairArgs, mesher: &Mesher<'_>) -> anyhow::Result<Vec<MeshCandidate>> {
    mesh_list(mesher, a.mesh_tolerances_m.as_deref(), a.hierarchies)
}

/// The mesh list: `tolerances_m` (default: the height range halved) over
/// `hierarchies`.
fn mesh_list(
    mesher: &Mesher<'_>,
    tolerances_m: Option<&[f64]>,
    hierarchies: Hierarchies,
) -> anyhow::Result<Vec<MeshCandidate>> {
    let mut opts = MeshListOptions::for_grid(mesher);
    if let Some(t) = tolerances_m {
        opts.tolerances_m = t.to_vec();
    }
    let quadtree = HierarchyKind::Quadtree(QuadOptions::DEFAULT);
    opts.hierarchies = match hierarchies {
        Hierarchies::Both => vec![HierarchyKind::Bitree, quadtree],
        Hierarchies::Bitree => vec![HierarchyKind::Bitree],
        Hierarchies::Quadtree => vec![quadtree],
    };
    let bytes = |m: &Mesh| textured_mesh_bytes(m.vertex_count(), m.triangle_count());
    let pb = crate::progress::bar(0, "listing meshes");
    let list = mesh_list_with_progress(mesher, &opts, &bytes, &pb.report());
    list.context("the mesh list")
}

/// The texture tolerances of `cota pair`'s default list, levels (its
/// `--texture-tolerances` default).
pub const DEFAULT_TEXTURE_TOLERANCES: [f64; 12] = [
    0.0, 2.0, 4.0, 8.0, 12.0, 16.0, 24.0, 32.0, 48.0, 64.0, 96.0, 128.0,
];

/// Paper 004's optimum pair for `grid` and its texture raster within
/// `budget_bytes` of textured GLB, from `cota pair`'s default lists (both
/// hierarchies, [`DEFAULT_TEXTURE_TOLERANCES`], weights 1): the chosen
/// texture level's PNG and the pair as [`pair_json`] says it.
pub fn best_pair(
    grid: &HeightGrid,
    texture: &RgbImage,
    budget_bytes: u64,
) -> anyhow::Result<(Vec<u8>, Value)> {
    let room = budget_bytes
        .checked_sub(FRAME_RESERVE_BYTES)
        .filter(|&r| r > 0);
    let Some(room) = room else {
        anyhow::bail!("--pair-budget-bytes: expected more than the {FRAME_RESERVE_BYTES} bytes kept for the GLB's header and JSON, found {budget_bytes}");
    };
    let textures = texture_list(texture, &DEFAULT_TEXTURE_TOLERANCES)?;
    let mesher = Mesher::new(grid);
    let meshes = mesh_list(&mesher, None, Hierarchies::Both)?;
    let mc: Vec<Candidate> = meshes.iter().map(|m| m.candidate()).collect();
    let tc: Vec<Candidate> = textures.iter().map(|t| t.candidate()).collect();
    let choice = choose(&mc, &tc, room, &PairOptions::DEFAULT).map_err(|e| match e {
        cota_core::pair::PairError::NothingFits { smallest, .. } if smallest < u64::MAX => anyhow::anyhow!(
            "--pair-budget-bytes: no (mesh, texture) pair fits in {budget_bytes} bytes: the smallest needs {}",
            smallest + FRAME_RESERVE_BYTES
        ),
        other => anyhow::anyhow!("--pair-budget-bytes: choosing the pair: {other}"),
    })?;
    let p = choice.optimum;
    let mut about = pair_json(&p, &meshes, &textures);
    about["budget_bytes"] = budget_bytes.into();
    about["meshes_listed"] = meshes.len().into();
    about["textures_listed"] = textures.len().into();
    let png = textures.into_iter().nth(p.texture).map(|t| t.png);
    Ok((png.unwrap_or_default(), about))
}

/// Every distinct pair total up to the largest, each chosen again: the
/// optimum "for every budget" (returns the budgets and the microseconds).
fn sweep(ms_: &[Candidate], ts: &[Candidate], opts: &PairOptions) -> (usize, f64) {
    let mut budgets: Vec<u64> = ms_
        .iter()
        .flat_map(|m| ts.iter().map(move |t| m.bytes + t.bytes))
        .collect();
    budgets.sort_unstable();
    budgets.dedup();
    let t = Instant::now();
    let found = budgets
        .iter()
        .filter(|&&b| choose(ms_, ts, b, opts).is_ok())
        .count();
    std::hint::black_box(found);
    (budgets.len(), t.elapsed().as_secs_f64() * 1e6)
}

pub fn run(a: &PairArgs) -> anyhow::Result<ExitCode> {
    validate(a)?;
    let t0 = Instant::now();
    let (grid, texture, about) = read_pair(a)?;
    let read_ms = ms(t0);
    let t = Instant::now();
    let textures = texture_list(&texture, &a.texture_tolerances)?;
    let mesher = Mesher::new(&grid);
    let meshes = meshes(a, &mesher)?;
    let lists_ms = ms(t);
    let (mc, tc): (Vec<Candidate>, Vec<Candidate>) = (
        meshes.iter().map(|m| m.candidate()).collect(),
        textures.iter().map(|t| t.candidate()).collect(),
    );
    let opts = PairOptions::DEFAULT
        .with_weights(a.alpha, a.beta)
        .with_polygons_within_texels(a.polygons_within_texels);
    let room = a.budget_bytes.saturating_sub(FRAME_RESERVE_BYTES);
    let t = Instant::now();
    let choice = choose(&mc, &tc, room, &opts).map_err(|e| budget_error(a, e))?;
    let choose_us = t.elapsed().as_secs_f64() * 1e6;
    let (budgets, sweep_us) = sweep(&mc, &tc, &opts);
    let pair = match (a.pick, choice.greedy) {
        (Pick::Greedy, Some(g)) => g,
        (Pick::Greedy, None) => anyhow::bail!(
            "--pick greedy: the paper's greedy scan finds no pair within {room} bytes"
        ),
        (Pick::Optimum, _) => choice.optimum,
    };
    let chosen = &meshes[pair.mesh];
    cota_core::check_mesh(&grid, &chosen.mesh, &chosen.check)
        .context("the invariant checker rejected the chosen mesh (this is a bug in cota)")?;
    let t = Instant::now();
    let spinner = crate::progress::spinner("writing");
    let written = write(a, &grid, &chosen.mesh, &textures[pair.texture].png)?;
    drop(spinner);
    let timing = json!({"read_ms": read_ms, "lists_ms": lists_ms, "choose_us": choose_us,
        "sweep_budgets": budgets, "sweep_us": sweep_us, "write_ms": ms(t)});
    let report = report(a, &about, &meshes, &textures, &choice, written, timing);
    let text = match a.json {
        true => format!("{}\n", serde_json::to_string_pretty(&report)?),
        false => text(&report),
    };
    crate::output::print_report(a.output.as_deref(), &text, a.json);
    Ok(ExitCode::SUCCESS)
}

/// Flags checked before any work.
fn validate(a: &PairArgs) -> anyhow::Result<()> {
    if let Some(out) = &a.output {
        check_glb_output(out, None, "cota pair writes a textured glTF")?;
    }
    for (flag, v) in [("--alpha", a.alpha), ("--beta", a.beta)] {
        if !(v.is_finite() && v >= 0.0) {
            anyhow::bail!("{flag}: expected a finite weight of 0 or more, found {v}");
        }
    }
    if a.budget_bytes <= FRAME_RESERVE_BYTES {
        anyhow::bail!(
            "--budget-bytes: expected more than the {FRAME_RESERVE_BYTES} bytes kept for the GLB's header and JSON, found {}",
            a.budget_bytes
        );
    }
    Ok(())
}

/// A budget no pair fits, in the words of the flags.
fn budget_error(a: &PairArgs, e: cota_core::pair::PairError) -> anyhow::Error {
    match e {
        cota_core::pair::PairError::NothingFits { smallest, .. } if smallest < u64::MAX => anyhow::anyhow!(
            "--budget-bytes: no (mesh, texture) pair fits in {} bytes: the smallest needs {} bytes ({smallest} for the pair + {FRAME_RESERVE_BYTES} for the GLB's frame)",
            a.budget_bytes,
            smallest + FRAME_RESERVE_BYTES
        ),
        other => anyhow::anyhow!("choosing the pair: {other}"),
    }
}

/// Encodes the GLB in memory, checks it against the budget, writes it
/// atomically; returns its size (0 without `-o`).
fn write(a: &PairArgs, grid: &HeightGrid, mesh: &Mesh, png: &[u8]) -> anyhow::Result<u64> {
    let mut bytes = Vec::new();
    write_glb_textured(&mut bytes, mesh, grid, png, &ExportOptions::DEFAULT)?;
    if bytes.len() as u64 > a.budget_bytes {
        anyhow::bail!(
            "the GLB would take {} bytes, over --budget-bytes {} (its frame exceeds the {FRAME_RESERVE_BYTES} bytes kept: a bug in cota)",
            bytes.len(),
            a.budget_bytes
        );
    }
    if let Some(out) = &a.output {
        crate::output::write_with(out, a.force.force, |w| Ok(w.write_all(&bytes)?))?;
    }
    Ok(bytes.len() as u64)
}

/// One chosen pair, for the report.
fn pair_json(
    p: &cota_core::pair::Pair,
    meshes: &[MeshCandidate],
    textures: &[TextureCandidate],
) -> Value {
    let (m, t) = (&meshes[p.mesh], &textures[p.texture]);
    json!({
        "mesh": p.mesh, "texture": p.texture, "bytes": p.bytes, "distortion": p.distortion,
        "hierarchy": m.hierarchy.name(), "tolerance_m": m.tolerance_m,
        "triangles": m.mesh.triangle_count(), "mesh_bytes": m.bytes, "d_mesh_m2": m.distortion_m2,
        "texture_tolerance": t.tolerance, "leaves": t.leaves, "texture_bytes": pad4(t.png.len() as u64),
        "d_texture": t.distortion,
    })
}

/// The JSON report (also the source of the text report).
fn report(
    a: &PairArgs,
    about: &Value,
    meshes: &[MeshCandidate],
    textures: &[TextureCandidate],
    choice: &Choice,
    glb_bytes: u64,
    timing: Value,
) -> Value {
    let ml: Vec<Value> = meshes
        .iter()
        .map(|m| {
            json!({"hierarchy": m.hierarchy.name(), "tolerance_m": m.tolerance_m,
            "vertices": m.mesh.vertex_count(), "triangles": m.mesh.triangle_count(),
            "d_mesh_m2": m.distortion_m2, "bytes": m.bytes})
        })
        .collect();
    let tl: Vec<Value> = textures
        .iter()
        .map(|t| json!({"tolerance": t.tolerance, "leaves": t.leaves, "d_texture": t.distortion,
            "bytes": pad4(t.png.len() as u64), "png_bytes": t.png.len(), "quadtree_bytes": t.quadtree_bytes}))
        .collect();
    let gap = choice.gap();
    json!({
        "dem": a.dem.display().to_string(),
        "image": about,
        "budget_bytes": a.budget_bytes,
        "frame_reserve_bytes": FRAME_RESERVE_BYTES,
        "byte_model": "GLB bytes: C(M) = positions (12/vertex) + TEXCOORD_0 (8/vertex) + indices (2 or 4 per corner), padded to 4; C(T) = the embedded PNG of the quadtree's flat-colour leaves at the texture raster's resolution, padded to 4; the file = C(M) + C(T) + its frame",
        "alpha": a.alpha, "beta": a.beta, "polygons_within_texels": a.polygons_within_texels,
        "meshes": ml, "textures": tl,
        "optimum": pair_json(&choice.optimum, meshes, textures),
        "greedy": choice.greedy.map(|g| pair_json(&g, meshes, textures)),
        "greedy_gap": gap,
        "greedy_gap_relative": gap.map(|g| g / choice.optimum.distortion.max(f64::MIN_POSITIVE)),
        "checked": true,
        "picked": if a.pick == Pick::Greedy { "greedy" } else { "optimum" },
        "glb_bytes": glb_bytes,
        "output": a.output.as_ref().map(|p| p.display().to_string()),
        "timing": timing,
    })
}

/// One pair as a line of the text report.
fn pair_line(p: &Value) -> String {
    format!(
        "{} at {} m ({} triangles, D(M) {:.4e} m2, {} B) + texture at {} ({} leaves, D(T) {}, {} B) = {} B, D {:.6e}",
        p["hierarchy"].as_str().unwrap_or(""),
        p["tolerance_m"],
        p["triangles"],
        p["d_mesh_m2"].as_f64().unwrap_or(0.0),
        p["mesh_bytes"],
        p["texture_tolerance"],
        p["leaves"],
        p["d_texture"],
        p["texture_bytes"],
        p["bytes"],
        p["distortion"].as_f64().unwrap_or(0.0)
    )
}

/// The text report.
fn text(r: &Value) -> String {
    let mut text = String::new();
    let txt = &mut text;
    let i = &r["image"];
    say!(
        txt,
        "dem         {} ({})",
        r["dem"].as_str().unwrap_or(""),
        i["dem_crs"].as_str().unwrap_or("")
    );
    say!(
        txt,
        "image       {} ({}, bands {}, {}), placed by {}",
        i["image"].as_str().unwrap_or(""),
        i["format"].as_str().unwrap_or(""),
        i["bands"].as_str().unwrap_or(""),
        i["image_crs"].as_str().unwrap_or(""),
        i["placement"].as_str().unwrap_or("")
    );
    say!(txt, "crs         {}", i["crs_rule"].as_str().unwrap_or(""));
    say!(
        txt,
        "texture     {} x {} texels, bilinear per channel",
        i["texture_size"][0],
        i["texture_size"][1]
    );
    let n = |k: &str| r[k].as_array().map_or(0, Vec::len);
    say!(
        txt,
        "lists       {} meshes, {} textures",
        n("meshes"),
        n("textures")
    );
    say!(
        txt,
        "budget      {} bytes ({} kept for the GLB frame)",
        r["budget_bytes"],
        r["frame_reserve_bytes"]
    );
    say!(txt, "optimum     {}", pair_line(&r["optimum"]));
    match r["greedy"].is_null() {
        true => say!(
            txt,
            "greedy      no pair (every fitting texture is smaller than its mesh)"
        ),
        false => say!(
            txt,
            "greedy      {}\ngap         {:.6e} ({:.2}% above the optimum)",
            pair_line(&r["greedy"]),
            r["greedy_gap"].as_f64().unwrap_or(0.0),
            100.0 * r["greedy_gap_relative"].as_f64().unwrap_or(0.0)
        ),
    }
    let t = &r["timing"];
    say!(txt,
        "time        read {:.1} ms, lists {:.1} ms, choose {:.1} us, every budget ({}) {:.1} us, write {:.1} ms",
        t["read_ms"].as_f64().unwrap_or(0.0),
        t["lists_ms"].as_f64().unwrap_or(0.0),
        t["choose_us"].as_f64().unwrap_or(0.0),
        t["sweep_budgets"],
        t["sweep_us"].as_f64().unwrap_or(0.0),
        t["write_ms"].as_f64().unwrap_or(0.0)
    );
    if let Some(out) = r["output"].as_str() {
        say!(
            txt,
            "wrote       {out} ({} bytes, {})",
            r["glb_bytes"],
            r["picked"].as_str().unwrap_or("")
        );
    }
    text
}

/// `cota mesh --texture`: writes `mesh` as a textured GLB with the whole
/// image draped. Returns `Ok(false)` when no texture was asked for.
pub fn write_draped(
    t: &TextureArgs,
    out: &Path,
    force: bool,
    grid: &HeightGrid,
    mesh: &Mesh,
    opts: &ExportOptions,
) -> anyhow::Result<bool> {
    let Some(image) = &t.texture else {
        return Ok(false);
    };
    let (texture, _) = drape_image(grid, image, &t.image)?;
    let png = encode_png(&texture)?;
    crate::output::write_with(out, force, |w| {
        write_glb_textured(w, mesh, grid, &png, opts).map(|_| ())
    })?;
    Ok(true)
}

/// `--texture` needs a .glb output and a plain triangle list.
pub fn check_texture(
    t: &TextureArgs,
    out: Option<&Path>,
    format: Option<MeshFormatArg>,
    strip: bool,
    quantize: bool,
) -> anyhow::Result<()> {
    if t.texture.is_none() {
        return Ok(());
    }
    match out {
        Some(o) => check_glb_output(o, format, "--texture writes a textured glTF")?,
        None => anyhow::bail!("--texture: expected -o OUT.glb, found no output"),
    }
    if strip || quantize {
        anyhow::bail!("--texture: expected a float triangle list, found --strip or --quantize");
    }
    Ok(())
}

/// A writable `.glb` output path, or standard output (`-`, taken as GLB
/// unless `format` says otherwise); `what` says why it must be one.
fn check_glb_output(out: &Path, format: Option<MeshFormatArg>, what: &str) -> anyhow::Result<()> {
    let format = format.or(is_dash(out).then_some(MeshFormatArg::Glb));
    if crate::output::check_output(out, format, None)? != cota_io::export::MeshFormat::Glb {
        anyhow::bail!("{}: {what}, expected a .glb output", out.display());
    }
    Ok(())
}
