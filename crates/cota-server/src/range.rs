//! HTTP `Range` requests (RFC 9110 §14) on the stream.
//!
//! * A `Range` the server cannot use is **ignored**, and the whole body is
//!   sent with 200 (§14.2): a unit other than `bytes`, a malformed or
//!   invalid ranges-specifier (`5-2`, `abc`, `-`), several `Range` header
//!   lines, a value longer than [`MAX_RANGE_HEADER`], or more than
//!   [`MAX_RANGES`] ranges (a broken client or a denial-of-service attempt).
//! * A valid range set none of whose ranges is satisfiable (all start at or
//!   past the end, or `-0`) is refused: 416 with `Content-Range: bytes */len`.
//! * The satisfiable ranges are sorted and overlapping or adjacent ones
//!   joined: one range left is sent as 206 with `Content-Range`; several
//!   as 206 `multipart/byteranges` ([`multipart`]).

use axum::http::header::{HeaderMap, RANGE};

use crate::error::{Result, ServeError};

/// Longest `Range` header value read; a longer one is ignored.
pub const MAX_RANGE_HEADER: usize = 1024;
/// Most ranges in one `Range`; more are ignored (the whole body is sent).
pub const MAX_RANGES: usize = 16;

/// What a `Range` header asks of a representation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Ranges {
    /// No `Range`, or one to ignore: the whole body (200).
    Whole,
    /// One inclusive byte range (206).
    One(u64, u64),
    /// Several disjoint inclusive byte ranges, ascending (206 multipart).
    Many(Vec<(u64, u64)>),
}

/// The ranges `headers` ask of a representation of `len` bytes.
///
/// # Errors
/// [`ServeError::RangeNotSatisfiable`] for a valid `bytes` range set none of
/// whose ranges lies within the `len` bytes.
pub fn parse_range(headers: &HeaderMap, len: u64) -> Result<Ranges> {
    let mut values = headers.get_all(RANGE).iter();
    let Some(value) = values.next() else {
        return Ok(Ranges::Whole);
    };
    if values.next().is_some() || value.len() > MAX_RANGE_HEADER {
        return Ok(Ranges::Whole);
    }
    let Ok(s) = value.to_str() else {
        return Ok(Ranges::Whole);
    };
    let Some(specs) = specs(s) else {
        return Ok(Ranges::Whole);
    };
    let mut wanted: Vec<(u64, u64)> = specs
        .into_iter()
        .filter_map(|spec| satisfiable(spec, len))
        .collect();
    if wanted.is_empty() {
        return Err(ServeError::RangeNotSatisfiable {
            range: s.chars().take(64).collect(),
            len,
        });
    }
    wanted.sort_unstable();
    let mut joined: Vec<(u64, u64)> = Vec::with_capacity(wanted.len());
    for (a, b) in wanted {
        match joined.last_mut() {
            Some(last) if a <= last.1.saturating_add(1) => last.1 = last.1.max(b),
            _ => joined.push((a, b)),
        }
    }
    Ok(match joined.as_slice() {
        [(a, b)] => Ranges::One(*a, *b),
        _ => Ranges::Many(joined),
    })
}

/// A range-spec: `first-last`, `first-` or `-suffix`.
type Spec = (Option<u64>, Option<u64>);

/// The range-specs of `bytes=…`, or `None` when the value is to be ignored.
fn specs(s: &str) -> Option<Vec<Spec>> {
    let (unit, set) = s.split_once('=')?;
    if !unit.trim().eq_ignore_ascii_case("bytes") {
        return None;
    }
    let mut out = Vec::new();
    for part in set.split(',') {
        let part = part.trim();
        if part.is_empty() {
            continue; // the list syntax allows empty elements
        }
        out.push(spec(part)?);
        if out.len() > MAX_RANGES {
            return None;
        }
    }
    (!out.is_empty()).then_some(out)
}

/// One range-spec, or `None` when it is malformed or invalid (`last < first`).
fn spec(part: &str) -> Option<Spec> {
    let (a, b) = part.split_once('-')?;
    let num = |t: &str| -> Option<Option<u64>> {
        let t = t.trim();
        if t.is_empty() {
            return Some(None);
        }
        if !t.bytes().all(|c| c.is_ascii_digit()) {
            return None;
        }
        // More digits than u64 holds: as good as infinity for a last-pos
        // or suffix, past any end for a first-pos.
        Some(Some(t.parse::<u64>().unwrap_or(u64::MAX)))
    };
    match (num(a)?, num(b)?) {
        (None, None) => None,
        (Some(x), Some(y)) if x > y => None,
        other => Some(other),
    }
}

/// The inclusive bytes of `spec` within `len` bytes, if any.
fn satisfiable(spec: Spec, len: u64) -> Option<(u64, u64)> {
    match spec {
        (Some(a), _) if a >= len => None,
        (Some(a), Some(b)) => Some((a, b.min(len - 1))),
        (Some(a), None) => Some((a, len - 1)),
        (None, Some(n)) if n > 0 && len > 0 => Some((len - n.min(len), len - 1)),
        _ => None,
    }
}

/// The boundary a multipart body of `parts` of `body` may use: one that
/// occurs in none of them (`None` if none found, then send the whole body).
pub fn boundary(body: &[u8], parts: &[(u64, u64)], seed: &str) -> Option<String> {
    (0..4u64).find_map(|k| {
        let b = format!(
            "cota-{:016x}",
            crate::stream::fnv64(format!("{seed}/{k}").as_bytes())
        );
        let dashed = format!("--{b}");
        let clash = parts.iter().any(|&(a, z)| {
            body.get(a as usize..=z as usize)
                .is_some_and(|p| p.windows(dashed.len()).any(|w| w == dashed.as_bytes()))
        });
        (!clash).then_some(b)
    })
}

/// The `multipart/byteranges` body (RFC 9110 §14.6) of `parts` of `body`,
/// each with `content_type` and its `Content-Range`.
pub fn multipart(body: &[u8], parts: &[(u64, u64)], content_type: &str, boundary: &str) -> Vec<u8> {
    let len = body.len();
    let mut out = Vec::new();
    for &(a, z) in parts {
        let head = format!(
            "\r\n--{boundary}\r\nContent-Type: {content_type}\r\nContent-Range: bytes {a}-{z}/{len}\r\n\r\n"
        );
        out.extend_from_slice(head.as_bytes());
        out.extend_from_slice(&body[a as usize..=z as usize]);
    }
    out.extend_from_slice(format!("\r\n--{boundary}--\r\n").as_bytes());
    out
}

#[cfg(test)]
mod test {
    use super::*;
    use axum::http::HeaderValue;

    fn range(v: &[&str], len: u64) -> Result<Ranges> {
        let mut h = HeaderMap::new();
        for s in v {
            h.append(RANGE, HeaderValue::from_str(s).unwrap());
        }
        parse_range(&h, len)
    }

    #[test]
    fn single_ranges() {
        let one = |v: &str, len| range(&[v], len).unwrap();
        assert_eq!(range(&[], 10).unwrap(), Ranges::Whole);
        assert_eq!(one("bytes=0-3", 10), Ranges::One(0, 3));
        assert_eq!(one("bytes=4-", 10), Ranges::One(4, 9));
        assert_eq!(one("bytes=-3", 10), Ranges::One(7, 9));
        assert_eq!(one("bytes=-30", 10), Ranges::One(0, 9));
        assert_eq!(one("bytes=5-99999", 10), Ranges::One(5, 9));
        assert_eq!(one("Bytes = 1-1", 10), Ranges::One(1, 1));
        assert_eq!(
            one("bytes=0-99999999999999999999999", 10),
            Ranges::One(0, 9)
        );
    }

    #[test]
    fn unusable_ranges_are_ignored() {
        let whole = |v: &[&str]| range(v, 10).unwrap() == Ranges::Whole;
        assert!(whole(&["bytes=0-1", "bytes=2-3"]), "two Range lines");
        assert!(whole(&["items=0-1"]), "unknown unit");
        assert!(whole(&["bytes=abc"]));
        assert!(whole(&["bytes=5-2"]), "last before first");
        assert!(whole(&["bytes=-"]));
        assert!(whole(&["bytes=+1-2"]));
        assert!(whole(&["bytes="]));
        assert!(whole(&["bytes=0-1,2-1"]), "one invalid spec spoils the set");
        assert!(whole(&[&format!("bytes=0-{}", "9".repeat(2000))]));
        let many: Vec<String> = (0..17).map(|k| format!("{}-{}", 3 * k, 3 * k)).collect();
        assert!(whole(&[&format!("bytes={}", many.join(","))]));
    }

    #[test]
    fn unsatisfiable_sets_are_416() {
        let unsat = |v: &str, len| {
            matches!(
                range(&[v], len),
                Err(ServeError::RangeNotSatisfiable { .. })
            )
        };
        assert!(unsat("bytes=10-", 10));
        assert!(unsat("bytes=-0", 10));
        assert!(unsat("bytes=18446744073709551615-", 10));
        assert!(unsat("bytes=10-12,20-", 10));
        assert!(unsat("bytes=0-", 0));
    }

    #[test]
    fn several_ranges_are_joined_and_sorted() {
        let r = |v: &str| range(&[v], 100).unwrap();
        assert_eq!(r("bytes=0-1,4-5"), Ranges::Many(vec![(0, 1), (4, 5)]));
        assert_eq!(
            r("bytes=50-60, 0-9, 200-"),
            Ranges::Many(vec![(0, 9), (50, 60)])
        );
        assert_eq!(r("bytes=0-9,5-20,21-30"), Ranges::One(0, 30));
        assert_eq!(r("bytes=-10,0-0"), Ranges::Many(vec![(0, 0), (90, 99)]));
    }

    #[test]
    fn multipart_body_holds_each_part() {
        let body: Vec<u8> = (0..100u8).collect();
        let parts = [(0, 1), (98, 99)];
        let b = boundary(&body, &parts, "x").unwrap();
        let m = multipart(&body, &parts, "application/octet-stream", &b);
        let text = String::from_utf8_lossy(&m);
        assert!(text.contains(&format!("--{b}\r\nContent-Type: application/octet-stream\r\nContent-Range: bytes 0-1/100\r\n\r\n")));
        assert!(text.contains("Content-Range: bytes 98-99/100"));
        assert!(m.ends_with(format!("\r\n--{b}--\r\n").as_bytes()));
        let clash = format!("--{b}");
        assert!(
            boundary(clash.as_bytes(), &[(0, clash.len() as u64 - 1)], "x").is_some_and(|c| c != b)
        );
    }
}
