//! Exact decisions for the samples whose floating-point error is too close
//! to the bound to tell.
//!
//! The scans ([`super::span`]) evaluate planes in `f64`; a sample whose
//! computed error is within a small margin of the bound `E` is decided here
//! in integers. Heights (`f32`) and `E` (`f64`) are dyadic rationals
//! `m·2^k`; scaled by a common power of two they become integers, and with
//! integer barycentric weights (cross products of the vertex positions) the
//! test `|plane(q) − h(q)| ≤ E` becomes `|Σ wᵢ·zᵢ − h·D| ≤ E·D` (`D` twice
//! the triangle's area), exact in `i128`. On integer SRTM heights many
//! samples sit at exactly `E` from a plane; deciding them exactly, rather
//! than rejecting everything in the margin, keeps about 9 % fewer triangles
//! at 1–5 m (the 1025² SRTM crop). When the scaled numbers would not fit,
//! the answer is "no" (the change is refused: safe).

/// `v` as `(m, k)` with `v = m·2^k` exactly, `m` odd or zero.
fn dyadic(v: f64) -> (i128, i32) {
    let bits = v.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32;
    let frac = (bits & ((1 << 52) - 1)) as i128;
    let (mut m, mut k) = if exp == 0 {
        (frac, -1074)
    } else {
        (frac | (1 << 52), exp - 1075)
    };
    if m == 0 {
        return (0, 0);
    }
    let tz = m.trailing_zeros();
    m >>= tz;
    k += tz as i32;
    if bits >> 63 == 1 {
        m = -m;
    }
    (m, k)
}

/// The values `vs` as integers `vᵢ·2^−K` for the smallest common `K`, or
/// `None` when one would need more than `bits` bits.
fn scaled<const N: usize>(vs: [f64; N], bits: u32) -> Option<[i128; N]> {
    let d = vs.map(dyadic);
    let k = d
        .iter()
        .filter(|x| x.0 != 0)
        .map(|x| x.1)
        .min()
        .unwrap_or(0);
    let mut out = [0i128; N];
    for (o, &(m, e)) in out.iter_mut().zip(d.iter()) {
        if m == 0 {
            continue;
        }
        let shift = (e - k) as u32;
        let width = 128 - m.unsigned_abs().leading_zeros();
        if shift + width > bits {
            return None;
        }
        *o = m << shift;
    }
    Some(out)
}

/// Whether `|plane(q) − h| ≤ e` exactly, for the plane through the
/// triangle `p` (counter-clockwise from above or not) at heights `z`.
pub(crate) fn plane_within(p: [[i32; 2]; 3], z: [f32; 3], q: [i32; 2], h: f32, e: f64) -> bool {
    let o = |a: [i32; 2], b: [i32; 2], c: [i32; 2]| -> i128 {
        let (ax, ay, bx, by, cx, cy) = (
            a[0] as i128,
            a[1] as i128,
            b[0] as i128,
            b[1] as i128,
            c[0] as i128,
            c[1] as i128,
        );
        (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    };
    let mut w = [o(q, p[1], p[2]), o(p[0], q, p[2]), o(p[0], p[1], q)];
    let mut d = o(p[0], p[1], p[2]);
    if d == 0 {
        return false;
    }
    if d < 0 {
        d = -d;
        w = w.map(|x| -x);
    }
    // |wᵢ| ≤ D: the scaled heights may use what the products and their
    // sum of four leave of an i128.
    let room = 124 - (128 - d.leading_zeros());
    let Some([z0, z1, z2, hs, es]) =
        scaled([z[0] as f64, z[1] as f64, z[2] as f64, h as f64, e], room)
    else {
        return false;
    };
    let lhs = (w[0] * z0 + w[1] * z1 + w[2] * z2 - hs * d).abs();
    lhs <= es * d
}

/// Whether `|chord(i) − h| ≤ e` exactly, for the chord from height `ha` at
/// 0 to `hb` at `len`, at position `i` (`0 ≤ i ≤ len`).
pub(crate) fn chord_within(len: i64, i: i64, ha: f32, hb: f32, h: f32, e: f64) -> bool {
    let (len, i) = (len as i128, i as i128);
    let room = 124 - (128 - len.leading_zeros());
    let Some([a, b, hs, es]) = scaled([ha as f64, hb as f64, h as f64, e], room) else {
        return false;
    };
    (a * (len - i) + b * i - hs * len).abs() <= es * len
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn dyadic_parts_are_exact() {
        for v in [0.0, 1.0, -3.5, 0.1, 3776.1f32 as f64, 1e-300, 5.0] {
            let (m, k) = dyadic(v);
            assert_eq!(m as f64 * 2f64.powi(k), v, "{v}");
        }
    }

    #[test]
    fn ties_are_within_and_anything_above_is_not() {
        // Plane z = x over a right triangle; a sample at height x - 5.
        let p = [[0, 0], [4, 0], [0, 4]];
        let z = [0.0, 4.0, 0.0];
        assert!(plane_within(p, z, [1, 1], -4.0, 5.0));
        assert!(!plane_within(p, z, [1, 1], -4.0, 4.999_999_999_999_999));
        assert!(!plane_within(p, z, [1, 1], -4.000_001, 5.0));
        // A plane with a third: z = (x + y) / 3 over (0,0) (3,0) (0,3)...
        let p = [[0, 0], [3, 0], [0, 3]];
        let z = [0.0, 1.0, 1.0];
        // at (1, 1): 2/3; h = 2/3 - 0.1 is not exact in f32, but the
        // decision is: |2/3 - h| ≤ e exactly.
        let h = (2.0f64 / 3.0 - 0.1) as f32;
        let exact = (2.0f64 / 3.0 - h as f64).abs();
        assert!(plane_within(p, z, [1, 1], h, exact + 1e-12));
        assert!(!plane_within(p, z, [1, 1], h, exact - 1e-12));
        // Orientation does not matter.
        assert!(plane_within(
            [[0, 0], [0, 3], [3, 0]],
            z.map(|x| x),
            [1, 1],
            h,
            exact + 1e-12
        ));
    }

    #[test]
    fn chords() {
        assert!(chord_within(4, 1, 0.0, 4.0, 6.0, 5.0));
        assert!(!chord_within(4, 1, 0.0, 4.0, 6.5, 5.0));
        assert!(chord_within(3, 1, 0.0, 1.0, 0.0, 1.0 / 3.0 + 1e-15));
        assert!(!chord_within(3, 1, 0.0, 1.0, 0.0, 1.0 / 3.0 - 1e-15));
    }
}
