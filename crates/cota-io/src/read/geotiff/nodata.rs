//! The GDAL_NODATA rule (tag 42113) and the conversion of samples to heights.
//!
//! The tag holds the nodata value as ASCII text. It is parsed as an f64 and then
//! converted to the sample type of the file, and samples are compared in that
//! type, as GDAL does:
//! * integer types: the value is rounded to the nearest integer; a value
//!   outside the type's range (or NaN/∞) matches no sample;
//! * Float32: the value is cast to f32, after snapping values within 1e-5 of
//!   ±f32::MAX to exactly ±f32::MAX, so that "-3.402823e+38" (FLT_MAX printed
//!   with 7 digits) matches the -f32::MAX samples written by GDAL, like the exact
//!   "-3.4028234663852886e+38";
//! * Float64: compared as parsed.
//!
//! "nan" declares NaN samples to be voids; any NaN in float data is a void anyway.

use crate::dem::DataType;
use crate::error::{malformed, ReadErrorKind};

/// Relative distance to ±f32::MAX within which a declared nodata is taken to
/// mean exactly ±f32::MAX (covers FLT_MAX printed with 6 or more digits).
const FLOAT_MAX_SNAP: f64 = 1e-5;

/// Parses the text of the GDAL_NODATA tag. `Ok(None)` for an empty tag.
///
/// # Errors
/// [`ReadErrorKind::Malformed`] when the text is not a number.
pub(super) fn parse_nodata(text: &str) -> Result<Option<f64>, ReadErrorKind> {
    let t = text.trim_matches(|c: char| c.is_whitespace() || c == '\0');
    if t.is_empty() {
        return Ok(None);
    }
    t.parse::<f64>()
        .map(Some)
        .map_err(|_| malformed("a number in the GDAL_NODATA tag 42113", format!("{t:?}")))
}

/// Snaps values that are ±f32::MAX printed with fewer digits to exactly ±f32::MAX.
fn snap_float_max(v: f64) -> f64 {
    let max = f64::from(f32::MAX);
    if (v.abs() - max).abs() <= FLOAT_MAX_SNAP * max {
        max.copysign(v)
    } else {
        v
    }
}

/// A sample type of the file, convertible to a height in metres.
pub(super) trait Sample: Copy + PartialEq {
    /// The declared nodata `v` as a value of this type, or `None` when it can
    /// match no sample of this type.
    fn nodata_as(v: f64) -> Option<Self>;

    /// The sample as an f32 (NaN stays NaN).
    fn to_f32(self) -> f32;

    /// The height of this sample: NaN when it equals `nodata`, else the value.
    #[inline]
    fn height(self, nodata: Option<Self>) -> f32 {
        if nodata == Some(self) {
            f32::NAN
        } else {
            self.to_f32()
        }
    }
}

macro_rules! integer_sample {
    ($($t:ty),*) => {$(
        impl Sample for $t {
            fn nodata_as(v: f64) -> Option<Self> {
                let r = v.round();
                // NaN and ±∞ fail both comparisons or the range test.
                if r >= f64::from(<$t>::MIN) && r <= f64::from(<$t>::MAX) {
                    Some(r as $t)
                } else {
                    None
                }
            }

            #[inline]
            fn to_f32(self) -> f32 {
                self as f32
            }
        }
    )*};
}

integer_sample!(i8, u8, i16, u16, i32, u32);

impl Sample for f32 {
    fn nodata_as(v: f64) -> Option<Self> {
        Some(snap_float_max(v) as f32)
    }

    #[inline]
    fn to_f32(self) -> f32 {
        self
    }
}

impl Sample for f64 {
    fn nodata_as(v: f64) -> Option<Self> {
        Some(v)
    }

    #[inline]
    fn to_f32(self) -> f32 {
        self as f32
    }
}

/// The declared nodata `v` as the file's samples see it (rounded for integer
/// types, cast to f32 for Float32), for [`crate::Dem::nodata`]. A value that
/// matches no sample of the type is returned as declared.
pub(super) fn effective_nodata(data_type: DataType, v: f64) -> f64 {
    fn via<T: Sample + Into<f64>>(v: f64) -> f64 {
        T::nodata_as(v).map_or(v, Into::into)
    }
    match data_type {
        DataType::I8 => via::<i8>(v),
        DataType::U8 => via::<u8>(v),
        DataType::I16 => via::<i16>(v),
        DataType::U16 => via::<u16>(v),
        DataType::I32 => via::<i32>(v),
        DataType::U32 => via::<u32>(v),
        DataType::F32 => via::<f32>(v),
        _ => v,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parsed(text: &str) -> f64 {
        match parse_nodata(text) {
            Ok(Some(v)) => v,
            other => panic!("{text:?} gave {other:?}"),
        }
    }

    #[test]
    fn parses_text_forms() {
        assert_eq!(parsed("-32768"), -32768.0);
        assert_eq!(parsed(" -9999\0"), -9999.0);
        assert_eq!(parsed("1e3"), 1000.0);
        assert!(parsed("nan").is_nan());
        assert!(parsed("NaN").is_nan());
        assert!(parsed("-nan").is_nan());
        assert!(matches!(parse_nodata(""), Ok(None)));
        assert!(matches!(parse_nodata("  \0"), Ok(None)));
        let err = parse_nodata("none").err().map(|e| e.to_string());
        assert_eq!(
            err.as_deref(),
            Some("expected a number in the GDAL_NODATA tag 42113, found \"none\"")
        );
    }

    #[test]
    fn float32_matches_float_max_printed_short_or_exact() {
        for text in [
            "-3.402823e+38",
            "-3.4028234663852886e+38",
            "-3.40282e+38",
            "-3.4028235e+38",
        ] {
            let nd = f32::nodata_as(parsed(text));
            assert_eq!(nd, Some(f32::MIN), "{text}");
            assert!(f32::MIN.height(nd).is_nan(), "{text}");
        }
        let nd = f32::nodata_as(parsed("3.402823e+38"));
        assert!(f32::MAX.height(nd).is_nan());
        // Near but not FLT_MAX printed: no snap.
        assert_eq!(f32::nodata_as(-3.3e38), Some(-3.3e38_f32));
        // A value not representable in f32 compares after the cast.
        let nd = f32::nodata_as(parsed("-999999.1"));
        assert!((-999_999.1_f32).height(nd).is_nan());
        assert_eq!((-999_999.0_f32).height(nd), -999_999.0);
    }

    #[test]
    fn float_nan_nodata_and_nan_samples_are_voids() {
        let nd = f32::nodata_as(f64::NAN);
        assert!(f32::NAN.height(nd).is_nan());
        assert_eq!(5.0_f32.height(nd), 5.0);
        // NaN is a void even without a declared nodata.
        assert!(f32::NAN.height(None).is_nan());
        assert!(f64::NAN.height(Some(-9999.0)).is_nan());
    }

    #[test]
    fn float64_compares_exactly() {
        let nd = f64::nodata_as(parsed("-9999"));
        assert!((-9999.0_f64).height(nd).is_nan());
        assert_eq!((-9_999.000_001_f64).height(nd), -9_999.000_001_f64 as f32);
    }

    #[test]
    fn integers_round_and_respect_the_type_range() {
        assert_eq!(i16::nodata_as(-32768.0), Some(i16::MIN));
        assert_eq!(i16::nodata_as(-32767.6), Some(i16::MIN));
        assert_eq!(i16::nodata_as(-32769.0), None);
        assert_eq!(u8::nodata_as(255.0), Some(255));
        assert_eq!(u8::nodata_as(256.0), None);
        assert_eq!(u8::nodata_as(-1.0), None);
        assert_eq!(u16::nodata_as(f64::NAN), None);
        assert_eq!(i32::nodata_as(f64::INFINITY), None);
        assert_eq!(u32::nodata_as(4_294_967_295.0), Some(u32::MAX));
        assert_eq!(i8::nodata_as(-128.0), Some(-128));
        assert_eq!(i8::nodata_as(128.0), None);
        // Out of range: matches nothing, not the clamped extreme.
        let nd = u8::nodata_as(-9999.0);
        assert_eq!(0_u8.height(nd), 0.0);
        assert!(i16::MIN.height(i16::nodata_as(-32768.0)).is_nan());
        assert_eq!((-32767_i16).height(i16::nodata_as(-32768.0)), -32767.0);
    }

    #[test]
    fn effective_value_is_in_the_sample_type() {
        assert_eq!(effective_nodata(DataType::I16, -32767.6), -32768.0);
        assert_eq!(effective_nodata(DataType::U8, -9999.0), -9999.0);
        assert_eq!(
            effective_nodata(DataType::F32, -3.402823e38),
            f64::from(f32::MIN)
        );
        assert_eq!(effective_nodata(DataType::F64, -3.402823e38), -3.402823e38);
        assert!(effective_nodata(DataType::F32, f64::NAN).is_nan());
    }
}
