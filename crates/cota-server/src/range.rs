//! HTTP `Range` requests on the stream (RFC 9110 §14): one range of bytes,
//! `a-b`, `a-` or `-n`. Anything else is refused with a 4xx rather than
//! ignored, so that a client never mistakes a whole stream for the part it
//! asked for: several `Range` headers or a malformed one give 400, several
//! ranges in one header or a range past the end give 416.

use axum::http::header::{HeaderMap, RANGE};

use crate::error::{Result, ServeError};

/// Longest `Range` header value read.
const MAX_RANGE_HEADER: usize = 256;

/// The inclusive byte range `Range` asks of a resource of `len` bytes:
/// `None` without a `Range` header.
///
/// # Errors
/// [`ServeError::BadRequest`] for several `Range` headers, a value that is not
/// ASCII, too long, not in `bytes=` units or not numbers;
/// [`ServeError::RangeNotSatisfiable`] for several ranges, an empty resource
/// or a range that starts at or past its end.
pub fn parse_range(headers: &HeaderMap, len: u64) -> Result<Option<(u64, u64)>> {
    let mut values = headers.get_all(RANGE).iter();
    let Some(value) = values.next() else {
        return Ok(None);
    };
    if values.next().is_some() {
        return Err(ServeError::BadRequest(
            "expected at most one Range header, found several".into(),
        ));
    }
    let bytes = value.as_bytes();
    if bytes.len() > MAX_RANGE_HEADER {
        return Err(ServeError::BadRequest(format!(
            "expected a Range header of at most {MAX_RANGE_HEADER} bytes, found {}",
            bytes.len()
        )));
    }
    let s = value
        .to_str()
        .map_err(|_| ServeError::BadRequest("expected an ASCII Range header".into()))?;
    let unsatisfiable = || ServeError::RangeNotSatisfiable {
        range: s.chars().take(64).collect(),
        len,
    };
    let spec = match s.split_once('=') {
        Some((unit, spec)) if unit.trim().eq_ignore_ascii_case("bytes") => spec.trim(),
        _ => {
            return Err(ServeError::BadRequest(format!(
                "expected a Range of the form bytes=FIRST-LAST, found {:?}",
                s.chars().take(64).collect::<String>()
            )))
        }
    };
    if spec.contains(',') {
        return Err(unsatisfiable());
    }
    let (first, last) = spec_bounds(spec)?;
    if len == 0 {
        return Err(unsatisfiable());
    }
    match (first, last) {
        (Some(a), _) if a >= len => Err(unsatisfiable()),
        (Some(a), Some(b)) => Ok(Some((a, b.min(len - 1)))),
        (Some(a), None) => Ok(Some((a, len - 1))),
        (None, Some(0)) => Err(unsatisfiable()),
        (None, Some(n)) => Ok(Some((len - n.min(len), len - 1))),
        (None, None) => Err(unsatisfiable()),
    }
}

/// `a-b`, `a-` or `-n` as numbers, `a ≤ b`.
fn spec_bounds(spec: &str) -> Result<(Option<u64>, Option<u64>)> {
    let bad = || {
        ServeError::BadRequest(format!(
            "expected a byte range FIRST-LAST, FIRST- or -SUFFIX of decimal numbers, found {:?}",
            spec.chars().take(64).collect::<String>()
        ))
    };
    let (a, b) = spec.split_once('-').ok_or_else(bad)?;
    let num = |t: &str| -> Result<Option<u64>> {
        let t = t.trim();
        if t.is_empty() {
            return Ok(None);
        }
        if t.len() > 19 || !t.bytes().all(|c| c.is_ascii_digit()) {
            return Err(bad());
        }
        t.parse::<u64>().map(Some).map_err(|_| bad())
    };
    let (a, b) = (num(a)?, num(b)?);
    match (a, b) {
        (None, None) => Err(bad()),
        (Some(x), Some(y)) if x > y => Err(bad()),
        _ => Ok((a, b)),
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use axum::http::HeaderValue;

    fn range(v: &[&str], len: u64) -> Result<Option<(u64, u64)>> {
        let mut h = HeaderMap::new();
        for s in v {
            h.append(RANGE, HeaderValue::from_str(s).unwrap());
        }
        parse_range(&h, len)
    }

    #[test]
    fn good_ranges() {
        assert_eq!(range(&[], 10).unwrap(), None);
        assert_eq!(range(&["bytes=0-3"], 10).unwrap(), Some((0, 3)));
        assert_eq!(range(&["bytes=4-"], 10).unwrap(), Some((4, 9)));
        assert_eq!(range(&["bytes=-3"], 10).unwrap(), Some((7, 9)));
        assert_eq!(range(&["bytes=-30"], 10).unwrap(), Some((0, 9)));
        assert_eq!(range(&["bytes=5-99999"], 10).unwrap(), Some((5, 9)));
        assert_eq!(range(&["Bytes = 1-1"], 10).unwrap(), Some((1, 1)));
    }

    #[test]
    fn bad_ranges_are_4xx() {
        let bad = |v: &[&str]| matches!(range(v, 10), Err(ServeError::BadRequest(_)));
        let unsat =
            |v: &[&str]| matches!(range(v, 10), Err(ServeError::RangeNotSatisfiable { .. }));
        assert!(bad(&["bytes=0-1", "bytes=2-3"]));
        assert!(bad(&["items=0-1"]));
        assert!(bad(&["bytes=abc"]));
        assert!(bad(&["bytes=5-2"]));
        assert!(bad(&["bytes=-"]));
        assert!(bad(&["bytes=99999999999999999999999-"]));
        assert!(bad(&["bytes=+1-2"]));
        assert!(bad(&[&format!("bytes=0-{}", "9".repeat(300))]));
        assert!(unsat(&["bytes=0-1,3-4"]));
        assert!(unsat(&["bytes=10-"]));
        assert!(unsat(&["bytes=-0"]));
        assert!(matches!(
            range(&["bytes=0-"], 0),
            Err(ServeError::RangeNotSatisfiable { .. })
        ));
    }
}
