//! The shaded-relief imagery through the router: `/imagery.json` names the
//! data's bounds and zooms; tiles over the data are 256² RGBA PNGs, opaque
//! over the data and transparent beyond it; decoded, their brightness
//! follows the DEM's own hillshade (Horn's slope, light from the north-west
//! at 45°, computed here from the DEM samples independently of the server's
//! code): among pixels of about one height (one tint), the correlation of
//! brightness and hillshade; tiles away from the data are 404, malformed
//! names 4xx; ETags revalidate.
#![allow(clippy::unwrap_used, clippy::panic, reason = "tests")]

use crate::common;

use std::sync::Arc;

use axum::body::{to_bytes, Body};
use axum::http::{header, Request, StatusCode};
use axum::Router;
use cota_core::HeightGrid;
use cota_server::{router, Imagery};
use tower::ServiceExt;

async fn get(
    app: &Router,
    uri: &str,
    h: &[(&str, &str)],
) -> (StatusCode, axum::http::HeaderMap, Vec<u8>) {
    let mut req = Request::get(uri);
    for (k, v) in h {
        req = req.header(*k, *v);
    }
    let r = app
        .clone()
        .oneshot(req.body(Body::empty()).unwrap())
        .await
        .unwrap();
    let (parts, body) = r.into_parts();
    (
        parts.status,
        parts.headers,
        to_bytes(body, usize::MAX).await.unwrap().to_vec(),
    )
}

/// RGBA pixels of a PNG.
fn decode(png_bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let mut d = png::Decoder::new(std::io::Cursor::new(png_bytes))
        .read_info()
        .unwrap();
    let mut buf = vec![0; d.output_buffer_size().unwrap()];
    let info = d.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgba);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Bilinear height of the DEM at a longitude and latitude (clamped).
fn height(g: &HeightGrid, lon: f64, lat: f64) -> f64 {
    let geo = g.georef();
    let (x0, y0) = geo.sample_xy(0.0, 0.0);
    let (x1, y1) = geo.sample_xy(1.0, 1.0);
    let c = ((lon - x0) / (x1 - x0)).clamp(0.0, (g.width() - 1) as f64);
    let r = ((lat - y0) / (y1 - y0)).clamp(0.0, (g.height() - 1) as f64);
    let (c0, r0) = (c.floor() as usize, r.floor() as usize);
    let (c1, r1) = ((c0 + 1).min(g.width() - 1), (r0 + 1).min(g.height() - 1));
    let (fc, fr) = (c - c0 as f64, r - r0 as f64);
    let z = |c, r| f64::from(g.get(c, r));
    (z(c0, r0) * (1.0 - fc) + z(c1, r0) * fc) * (1.0 - fr)
        + (z(c0, r1) * (1.0 - fc) + z(c1, r1) * fc) * fr
}

/// The DEM's hillshade at a point, from heights one pixel (`d` degrees) apart.
fn hillshade(g: &HeightGrid, lon: f64, lat: f64, d: f64) -> f64 {
    let h = |i: f64, j: f64| height(g, lon + i * d, lat - j * d);
    let dx = d * 111_320.0 * lat.to_radians().cos();
    let dy = d * 110_574.0;
    let east =
        (h(1., -1.) + 2. * h(1., 0.) + h(1., 1.)) - (h(-1., -1.) + 2. * h(-1., 0.) + h(-1., 1.));
    let north =
        (h(-1., -1.) + 2. * h(0., -1.) + h(1., -1.)) - (h(-1., 1.) + 2. * h(0., 1.) + h(1., 1.));
    let (gx, gy) = (east / (8. * dx), north / (8. * dy));
    let (az, alt) = (315f64.to_radians(), 45f64.to_radians());
    let l = [az.sin() * alt.cos(), az.cos() * alt.cos(), alt.sin()];
    ((-gx * l[0] - gy * l[1] + l[2]) / (gx * gx + gy * gy + 1.).sqrt()).max(0.0)
}

/// Each value less the mean of its group (pixels of about one height).
fn within_groups(v: &[f64], group: &[usize]) -> Vec<f64> {
    let n = group.iter().max().map_or(0, |g| g + 1);
    let (mut sum, mut count) = (vec![0.0; n], vec![0.0; n]);
    for (x, &g) in v.iter().zip(group) {
        sum[g] += x;
        count[g] += 1.0;
    }
    v.iter()
        .zip(group)
        .map(|(x, &g)| x - sum[g] / count[g])
        .collect()
}

fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

#[tokio::test]
async fn relief_tiles_follow_the_dem_s_hillshade() {
    let grid = common::grid();
    let app = router(common::state().with_imagery(Imagery::new(Arc::new(grid.clone())).unwrap()));
    let (s, _, b) = get(&app, "/imagery.json", &[]).await;
    assert_eq!(s, StatusCode::OK);
    let meta: serde_json::Value = serde_json::from_slice(&b).unwrap();
    let z = meta["maxzoom"].as_u64().unwrap() as u32;
    let bounds: Vec<f64> = meta["bounds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(meta["tiles"][0], "imagery/{z}/{x}/{y}.png");
    // The tile (TMS) under the data's centre at the finest zoom.
    let d_tile = 180.0 / f64::from(1u32 << z);
    let (lon, lat) = ((bounds[0] + bounds[2]) / 2.0, (bounds[1] + bounds[3]) / 2.0);
    let (x, y) = (
        ((lon + 180.0) / d_tile) as u32,
        ((lat + 90.0) / d_tile) as u32,
    );
    let uri = format!("/imagery/{z}/{x}/{y}.png");
    let (s, h, png) = get(&app, &uri, &[]).await;
    assert_eq!(s, StatusCode::OK, "{uri}");
    assert_eq!(h[header::CONTENT_TYPE], "image/png");
    let (w, ht, px) = decode(&png);
    assert_eq!((w, ht), (256, 256));
    let (west, north) = (
        -180.0 + f64::from(x) * d_tile,
        -90.0 + f64::from(y + 1) * d_tile,
    );
    let d = d_tile / 256.0;
    let (mut lum, mut shade, mut band) = (Vec::new(), Vec::new(), Vec::new());
    let (mut inside, mut outside) = (0, 0);
    for j in 0..256 {
        for i in 0..256 {
            let (plon, plat) = (
                west + (f64::from(i) + 0.5) * d,
                north - (f64::from(j) + 0.5) * d,
            );
            let p = &px[((j * 256 + i) * 4) as usize..][..4];
            let within = plon > bounds[0] + d
                && plon < bounds[2] - d
                && plat > bounds[1] + d
                && plat < bounds[3] - d;
            let beyond = plon < bounds[0] - d
                || plon > bounds[2] + d
                || plat < bounds[1] - d
                || plat > bounds[3] + d;
            if within {
                assert_eq!(p[3], 255, "opaque over the data at {plon}, {plat}");
                inside += 1;
                lum.push(
                    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]),
                );
                shade.push(hillshade(&grid, plon, plat, d));
                band.push((height(&grid, plon, plat).max(0.0) / 25.0) as usize);
            } else if beyond {
                assert_eq!(p[3], 0, "transparent beyond the data at {plon}, {plat}");
                outside += 1;
            }
        }
    }
    let all = pearson(&lum, &shade);
    let r = pearson(&within_groups(&lum, &band), &within_groups(&shade, &band));
    println!(
        "{uri}: {inside} pixels over the data, {outside} beyond; brightness against the DEM's \
         hillshade: r = {r:.3} within 25 m height bands ({all:.3} over all pixels, the tint mixed in)"
    );
    assert!(inside > 10_000, "{inside}");
    assert!(
        r > 0.9,
        "brightness against the DEM's hillshade: r = {r:.3}"
    );
    // Validators, and tiles that are not there.
    let etag = h[header::ETAG].to_str().unwrap().to_string();
    assert_eq!(
        get(&app, &uri, &[("if-none-match", &etag)]).await.0,
        StatusCode::NOT_MODIFIED
    );
    for (bad, status) in [
        (format!("/imagery/{z}/0/0.png"), StatusCode::NOT_FOUND),
        (
            format!("/imagery/{}/{x}/{y}.png", z + 1),
            StatusCode::NOT_FOUND,
        ),
        ("/imagery/0/5/0.png".into(), StatusCode::BAD_REQUEST),
        ("/imagery/0/0/0.jpg".into(), StatusCode::BAD_REQUEST),
        ("/imagery/a/0/0.png".into(), StatusCode::BAD_REQUEST),
    ] {
        assert_eq!(get(&app, &bad, &[]).await.0, status, "{bad}");
    }
    // Zoom 0 holds the data too (west or east half of the world).
    let zero = if lon < 0.0 {
        "/imagery/0/0/0.png"
    } else {
        "/imagery/0/1/0.png"
    };
    assert_eq!(get(&app, zero, &[]).await.0, StatusCode::OK);
}
