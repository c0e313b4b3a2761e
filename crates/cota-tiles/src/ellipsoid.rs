//! WGS 84 geometry for the quantized-mesh header: geodetic to Earth-centred
//! fixed (ECEF) coordinates, the bounding sphere, the horizon occlusion
//! point, and oct-encoded normals.
//!
//! References: the quantized-mesh-1.0 specification (CesiumGS/quantized-mesh;
//! the header's horizon occlusion point is "expressed in the ellipsoid-scaled
//! Earth-centered Fixed frame"), Cesium's "Horizon culling" article (2013:
//! scale space by the ellipsoid's radii so the ellipsoid becomes the unit
//! sphere; a point `P` is hidden behind the horizon when the cone of
//! tangents from the camera hides it; the occlusion point is the point on a
//! chosen direction that is hidden exactly when every vertex is), and Cigolle
//! et al. 2014, "A Survey of Efficient Representations of Independent Unit
//! Vectors" (the octahedral encoding).

/// WGS 84 semi-major axis, metres.
pub const A_M: f64 = 6_378_137.0;
/// WGS 84 semi-minor axis, metres.
pub const B_M: f64 = 6_356_752.314_245_179;

/// ECEF metres of a geodetic position (degrees, metres above the ellipsoid).
pub fn ecef(lon_deg: f64, lat_deg: f64, h_m: f64) -> [f64; 3] {
    let (lon, lat) = (lon_deg.to_radians(), lat_deg.to_radians());
    let e2 = 1.0 - (B_M * B_M) / (A_M * A_M);
    let n = A_M / (1.0 - e2 * lat.sin() * lat.sin()).sqrt();
    [
        (n + h_m) * lat.cos() * lon.cos(),
        (n + h_m) * lat.cos() * lon.sin(),
        (n * (1.0 - e2) + h_m) * lat.sin(),
    ]
}

/// The geodetic longitude, latitude (degrees) and height (metres) of an
/// ECEF position: the inverse of [`ecef`], by fixed-point iteration on the
/// latitude (converges to well under a millimetre in a few steps away from
/// the Earth's centre).
pub fn geodetic(p: [f64; 3]) -> [f64; 3] {
    let e2 = 1.0 - (B_M * B_M) / (A_M * A_M);
    let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
    let lon = p[1].atan2(p[0]);
    let mut lat = p[2].atan2(r * (1.0 - e2));
    let mut h = 0.0;
    for _ in 0..10 {
        let s = lat.sin();
        let n = A_M / (1.0 - e2 * s * s).sqrt();
        // Near the poles the height from the z axis is better conditioned.
        h = if lat.cos().abs() > 1e-3 {
            r / lat.cos() - n
        } else {
            p[2] / s - n * (1.0 - e2)
        };
        lat = p[2].atan2(r * (1.0 - e2 * n / (n + h)));
    }
    [lon.to_degrees(), lat.to_degrees(), h]
}

/// The east, north, up unit vectors in ECEF at a geodetic position.
pub fn enu_axes(lon_deg: f64, lat_deg: f64) -> [[f64; 3]; 3] {
    let (lon, lat) = (lon_deg.to_radians(), lat_deg.to_radians());
    [
        [-lon.sin(), lon.cos(), 0.0],
        [-lat.sin() * lon.cos(), -lat.sin() * lon.sin(), lat.cos()],
        [lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin()],
    ]
}

/// A sphere holding every point: the centre of their bounding box and the
/// largest distance to it.
pub fn bounding_sphere(points: &[[f64; 3]]) -> ([f64; 3], f64) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let c = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
    let r = points.iter().map(|p| dist(*p, c)).fold(0.0, f64::max);
    (c, r)
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn scaled(p: [f64; 3]) -> [f64; 3] {
    [p[0] / A_M, p[1] / A_M, p[2] / B_M]
}

fn norm(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

/// The horizon occlusion point in ellipsoid-scaled ECEF: on the ray from the
/// Earth's centre through `direction` (the bounding sphere's centre), the
/// point nearest the centre that is hidden only when every one of `points`
/// is. In scaled space, a point at distance `d ≥ 1` from the centre, at
/// angle `α` from the ray, sees the horizon at angle `β = acos(1/d)`; the
/// occlusion point on the ray must be at `1 / cos(α + β)`. `None` when a
/// point is a quarter turn or more from the ray (`α + β ≥ 90°`: a tile wider
/// than a hemisphere's horizon, the root tiles), where no such point exists.
pub fn horizon_occlusion_point(direction: [f64; 3], points: &[[f64; 3]]) -> Option<[f64; 3]> {
    let d = scaled(direction);
    let len = norm(d);
    if len == 0.0 {
        return None;
    }
    let u = d.map(|c| c / len);
    let mut magnitude = 0f64;
    for p in points {
        let q = scaled(*p);
        let m = norm(q).max(1.0);
        let dir = q.map(|c| c / norm(q).max(f64::MIN_POSITIVE));
        let cos_a = dir[0] * u[0] + dir[1] * u[1] + dir[2] * u[2];
        let cross = [
            dir[1] * u[2] - dir[2] * u[1],
            dir[2] * u[0] - dir[0] * u[2],
            dir[0] * u[1] - dir[1] * u[0],
        ];
        let sin_a = norm(cross);
        let cos_b = 1.0 / m;
        let sin_b = (m * m - 1.0).max(0.0).sqrt() * cos_b;
        let denom = cos_a * cos_b - sin_a * sin_b;
        if denom <= 1e-12 {
            return None;
        }
        magnitude = magnitude.max(1.0 / denom);
    }
    Some(u.map(|c| c * magnitude))
}

/// The octahedral encoding of a unit vector in two bytes (each component
/// mapped from [−1, 1] to 0..=255).
pub fn oct_encode(n: [f64; 3]) -> [u8; 2] {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    if l1 == 0.0 {
        return [128, 128];
    }
    let (mut x, mut y) = (n[0] / l1, n[1] / l1);
    if n[2] < 0.0 {
        let sign = |v: f64| if v < 0.0 { -1.0 } else { 1.0 };
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * sign(ox);
        y = (1.0 - ox.abs()) * sign(oy);
    }
    let snorm = |v: f64| ((v.clamp(-1.0, 1.0) * 0.5 + 0.5) * 255.0).round() as u8;
    [snorm(x), snorm(y)]
}

/// The unit vector of an octahedral encoding (the inverse of [`oct_encode`],
/// up to its rounding).
pub fn oct_decode(e: [u8; 2]) -> [f64; 3] {
    let f = |b: u8| f64::from(b) / 255.0 * 2.0 - 1.0;
    let (mut x, mut y) = (f(e[0]), f(e[1]));
    let z = 1.0 - x.abs() - y.abs();
    if z < 0.0 {
        let sign = |v: f64| if v < 0.0 { -1.0 } else { 1.0 };
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * sign(ox);
        y = (1.0 - ox.abs()) * sign(oy);
    }
    let l = norm([x, y, z]);
    [x / l, y / l, z / l]
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn ecef_of_known_points() {
        let p = ecef(0.0, 0.0, 0.0);
        assert!((p[0] - A_M).abs() < 1e-6 && p[1].abs() < 1e-6 && p[2].abs() < 1e-6);
        let n = ecef(0.0, 90.0, 0.0);
        assert!((n[2] - B_M).abs() < 1e-6);
    }

    #[test]
    fn geodetic_inverts_ecef() {
        for (lon, lat, h) in [
            (10.5, 47.25, 1234.5),
            (-71.3, -28.7, -12.0),
            (179.9, 89.99, 8000.0),
            (0.0, 0.0, -6000.0),
        ] {
            let [a, b, c] = geodetic(ecef(lon, lat, h));
            assert!((a - lon).abs() < 1e-9 && (b - lat).abs() < 1e-9, "{a} {b}");
            assert!((c - h).abs() < 1e-4, "{c} {h}");
        }
    }

    #[test]
    fn occlusion_point_is_beyond_the_points_and_hides_with_them() {
        let pts: Vec<[f64; 3]> = [(10.0, 0.0), (10.1, 0.0), (10.0, 0.1), (10.1, 0.1)]
            .iter()
            .map(|&(lo, la)| ecef(lo, la, 1000.0))
            .collect();
        let (c, _) = bounding_sphere(&pts);
        let p = horizon_occlusion_point(c, &pts).unwrap();
        let m = norm(p);
        assert!(m > 1.0 && m < 1.01, "{m}");
        // A root tile spans a hemisphere: no occlusion point.
        let root: Vec<[f64; 3]> = [
            (0.0, -90.0),
            (180.0, 90.0),
            (90.0, 0.0),
            (0.0, 0.0),
            (180.0, 0.0),
        ]
        .iter()
        .map(|&(lo, la)| ecef(lo, la, 0.0))
        .collect();
        let (c, _) = bounding_sphere(&root);
        assert!(horizon_occlusion_point(c, &root).is_none());
    }

    #[test]
    fn oct_round_trip() {
        for n in [
            [0.0, 0.0, 1.0],
            [0.6, 0.0, 0.8],
            [0.0, -0.6, -0.8],
            [-0.48, 0.6, 0.64],
        ] {
            let d = oct_decode(oct_encode(n));
            let dot = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
            assert!(dot > 0.999, "{n:?} {d:?}");
        }
    }
}
