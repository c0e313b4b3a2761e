//! The parameters of a PROJ string, as far as cota reads them itself (which
//! datum shift it asks for, whether it is longitude/latitude); the
//! projection math is proj4rs's.
//!
//! Reference: PROJ's string syntax and parameters
//! (<https://proj.org/usage/projections.html>: `+key=value` tokens, values
//! quoted with `"` when they hold blanks; `+datum`, `+towgs84`, `+nadgrids`,
//! `+ellps`, `+a`/`+b`/`+rf`; `+proj=longlat` and its aliases).

/// One `+key[=value]` token.
#[derive(Debug, Clone, PartialEq)]
struct Param {
    key: String,
    value: Option<String>,
}

/// The tokens of a PROJ string, in order.
#[derive(Debug, Clone, PartialEq)]
pub struct ProjParams {
    params: Vec<Param>,
}

/// Semi-major axis of WGS 84 and GRS 1980, metres.
const WGS84_A: f64 = 6_378_137.0;
/// Semi-minor axes of WGS 84 and GRS 1980, metres (they differ by 0.1 mm).
const WGS84_B: f64 = 6_356_752.314_245;
const GRS80_B: f64 = 6_356_752.314_140;

impl ProjParams {
    /// Splits `text` into `+key[=value]` tokens; `None` when a token does
    /// not start with `+`, a key is empty or a quote is not closed.
    pub fn parse(text: &str) -> Option<ProjParams> {
        let mut params = Vec::new();
        let mut rest = text.trim_start();
        while !rest.is_empty() {
            let body = rest.strip_prefix('+')?;
            let key_len = body
                .find(|c: char| c == '=' || c.is_whitespace())
                .unwrap_or(body.len());
            let key = &body[..key_len];
            if key.is_empty() || !key.chars().all(|c| c.is_alphanumeric() || c == '_') {
                return None;
            }
            let after = &body[key_len..];
            let (value, tail) = match after.strip_prefix('=') {
                Some(v) => split_value(v)?,
                None => (None, after),
            };
            params.push(Param {
                key: key.to_string(),
                value,
            });
            rest = tail.trim_start();
        }
        Some(ProjParams { params })
    }

    /// The value of the first `+key=value`.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.params
            .iter()
            .find(|p| p.key == key)
            .and_then(|p| p.value.as_deref())
    }

    /// True when `+key` is present, with or without a value.
    pub fn has(&self, key: &str) -> bool {
        self.params.iter().any(|p| p.key == key)
    }

    /// The projection's name (`+proj=`).
    pub fn proj(&self) -> Option<&str> {
        self.get("proj")
    }

    /// True for longitude/latitude (`+proj=longlat` and its aliases).
    pub fn is_geographic(&self) -> bool {
        matches!(
            self.proj(),
            Some("longlat" | "latlong" | "lonlat" | "latlon")
        )
    }

    /// The `+towgs84` numbers, when present and all numbers.
    pub fn towgs84(&self) -> Option<Vec<f64>> {
        let v = self.get("towgs84")?;
        v.split(',').map(|s| s.trim().parse::<f64>().ok()).collect()
    }

    /// The text with `+title` (a description, not a parameter) left out.
    pub fn without_title(&self) -> String {
        let mut out = Vec::new();
        for p in self.params.iter().filter(|p| p.key != "title") {
            out.push(match &p.value {
                Some(v) if v.contains(char::is_whitespace) => format!("+{}=\"{v}\"", p.key),
                Some(v) => format!("+{}={v}", p.key),
                None => format!("+{}", p.key),
            });
        }
        out.join(" ")
    }

    /// The `+title` (a description the definition carries), if any.
    pub fn title(&self) -> Option<&str> {
        self.get("title")
    }
}

/// A value after `=`: quoted (up to the closing `"`) or up to the next blank.
/// Returns the value and the rest of the text.
fn split_value(v: &str) -> Option<(Option<String>, &str)> {
    if let Some(quoted) = v.strip_prefix('"') {
        let end = quoted.find('"')?;
        return Some((Some(quoted[..end].to_string()), &quoted[end + 1..]));
    }
    let end = v.find(char::is_whitespace).unwrap_or(v.len());
    Some((Some(v[..end].to_string()), &v[end..]))
}

/// True when an ellipsoid of axes `a`, `b` (metres) is WGS 84's or GRS
/// 1980's, to 1 mm.
pub fn is_wgs84_like_ellipsoid(a: f64, b: f64) -> bool {
    (a - WGS84_A).abs() < 1e-3 && [WGS84_B, GRS80_B].iter().any(|w| (b - w).abs() < 1e-3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_values_and_quotes() {
        let p = ProjParams::parse(
            "+proj=utm +zone=25 +south +towgs84=0,0,0 +title=\"UTM 25, south\" +no_defs",
        )
        .unwrap();
        assert_eq!(p.proj(), Some("utm"));
        assert_eq!(p.get("zone"), Some("25"));
        assert!(p.has("south") && p.get("south").is_none());
        assert_eq!(p.towgs84(), Some(vec![0.0, 0.0, 0.0]));
        assert_eq!(p.title(), Some("UTM 25, south"));
        assert_eq!(
            p.without_title(),
            "+proj=utm +zone=25 +south +towgs84=0,0,0 +no_defs"
        );
        assert!(!p.is_geographic());
        assert!(ProjParams::parse("+proj=latlong +datum=WGS84")
            .unwrap()
            .is_geographic());
        for bad in ["proj=utm", "+=3", "+proj=utm +title=\"open", "+a-b=1"] {
            assert_eq!(ProjParams::parse(bad), None, "{bad}");
        }
        assert_eq!(ProjParams::parse("+towgs84=1,x").unwrap().towgs84(), None);
    }

    #[test]
    fn wgs84_like() {
        assert!(is_wgs84_like_ellipsoid(6_378_137.0, 6_356_752.314_245_18));
        assert!(is_wgs84_like_ellipsoid(6_378_137.0, 6_356_752.314_140_36));
        assert!(!is_wgs84_like_ellipsoid(6_377_563.396, 6_356_256.909));
        assert!(!is_wgs84_like_ellipsoid(6_378_137.0, 6_378_137.0));
    }
}
