//! ESRI ASCII grids: a header of `key value` lines (`ncols`, `nrows`,
//! `xllcorner`/`xllcenter`, `yllcorner`/`yllcenter`, `cellsize`, optional
//! `NODATA_value`), then the values row by row from the north. A value equal
//! to the nodata value (as `f64` or as `f32`) is a void; values are parsed as
//! `f64` and rounded to `f32`, as `cota-io` does.

use crate::{Place, Samples};

/// Parses an ESRI ASCII grid.
pub(crate) fn parse(bytes: &[u8]) -> Result<Samples, String> {
    let text = std::str::from_utf8(bytes).map_err(|e| format!("expected UTF-8 text ({e})"))?;
    let mut tokens = text.split_ascii_whitespace().peekable();
    let (mut ncols, mut nrows, mut cell, mut nodata) = (None, None, None, None);
    let (mut x, mut y, mut centre) = (0.0, 0.0, false);
    while let Some(&key) = tokens.peek() {
        if key.parse::<f64>().is_ok() {
            break;
        }
        tokens.next();
        let value = tokens
            .next()
            .ok_or_else(|| format!("expected a value after {key}"))?;
        let v: f64 = value
            .parse()
            .map_err(|_| format!("expected a number after {key}, found {value}"))?;
        match key.to_ascii_lowercase().as_str() {
            "ncols" => ncols = Some(v as usize),
            "nrows" => nrows = Some(v as usize),
            "xllcorner" => x = v,
            "yllcorner" => y = v,
            "xllcenter" => (x, centre) = (v, true),
            "yllcenter" => (y, centre) = (v, true),
            "cellsize" => cell = Some(v),
            "nodata_value" => nodata = Some(v),
            other => return Err(format!("unexpected header key {other}")),
        }
    }
    let (Some(width), Some(height), Some(cell)) = (ncols, nrows, cell) else {
        return Err("expected ncols, nrows and cellsize in the header".to_string());
    };
    let heights = tokens
        .map(|t| {
            let v: f64 = t
                .parse()
                .map_err(|_| format!("expected a number, found {t}"))?;
            Ok(match nodata {
                Some(nd) if v == nd || v as f32 == nd as f32 => f32::NAN,
                _ => v as f32,
            })
        })
        .collect::<Result<Vec<f32>, String>>()?;
    if heights.len() != width * height {
        return Err(format!(
            "expected {width}x{height} = {} values, found {}",
            width * height,
            heights.len()
        ));
    }
    Ok(Samples {
        width,
        height,
        heights,
        place: Place::Ascii {
            x_ll: x,
            y_ll: y,
            cell,
            centre,
        },
    })
}
