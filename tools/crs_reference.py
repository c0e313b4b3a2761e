#!/usr/bin/env python3
"""Reference points for cota's map projections, computed with PROJ (pyproj).

Writes crates/cota-io/tests/data/crs_reference.json, which
crates/cota-io/tests/suite/crs.rs checks cota's transforms against (1 mm in
projected metres, 1e-8 degrees in longitude/latitude).

For each CRS: about 20 points spread over its area of use (from PROJ's
database), forward (WGS 84 lon/lat -> x/y) and inverse (x/y -> lon/lat).

Which PROJ operation is the reference: cota defines an EPSG code by the PROJ
string of the `crs-definitions` crate (recorded here as `proj_cota`). PROJ
itself, given `EPSG:N` or a `+datum=` name, may choose among several
transformations to WGS 84 (grids, regional Helmerts), so the reference uses
the same string with each `+datum=NAME` written out as the ellipsoid and the
`+towgs84` Helmert that the PROJ 4 datum table gives it (and proj4rs uses):
both sides then apply the same Helmert, and the JSON records the pipeline PROJ
ran (`operation`). Grid-based transformations (OSTN15 for EPSG:27700, NADCON
for NAD27) are out of scope. Web Mercator's reference is PROJ's own EPSG:3857.

Run: python3 tools/crs_reference.py   (pip install pyproj)
"""

import json
import os

import pyproj
from pyproj import CRS, Transformer

WGS84 = "+proj=longlat +datum=WGS84 +no_defs +type=crs"

# The definitions of crs-definitions 0.6 (EPSG code -> PROJ string), as cota
# reads them; crs.rs checks that the crate still gives these.
CRSS = {
    32633: "+proj=utm +zone=33 +datum=WGS84 +units=m +no_defs",
    32725: "+proj=utm +zone=25 +south +datum=WGS84 +units=m +no_defs",
    26910: "+proj=utm +zone=10 +datum=NAD83 +units=m +no_defs",
    26916: "+proj=utm +zone=16 +datum=NAD83 +units=m +no_defs",
    27700: "+proj=tmerc +lat_0=49 +lon_0=-2 +k=0.9996012717 +x_0=400000 "
    "+y_0=-100000 +datum=OSGB36 +units=m +no_defs",
    2193: "+proj=tmerc +lat_0=0 +lon_0=173 +k=0.9996 +x_0=1600000 "
    "+y_0=10000000 +ellps=GRS80 +towgs84=0,0,0,0,0,0,0 +units=m +no_defs",
    31985: "+proj=utm +zone=25 +south +ellps=GRS80 +towgs84=0,0,0,0,0,0,0 "
    "+units=m +no_defs",
    3035: "+proj=laea +lat_0=52 +lon_0=10 +x_0=4321000 +y_0=3210000 "
    "+ellps=GRS80 +towgs84=0,0,0,0,0,0,0 +units=m +no_defs",
    2154: "+proj=lcc +lat_1=49 +lat_2=44 +lat_0=46.5 +lon_0=3 +x_0=700000 "
    "+y_0=6600000 +ellps=GRS80 +towgs84=0,0,0,0,0,0,0 +units=m +no_defs",
    3347: "+proj=lcc +lat_1=49 +lat_2=77 +lat_0=63.390675 "
    "+lon_0=-91.86666666666666 +x_0=6200000 +y_0=3000000 +datum=NAD83 "
    "+units=m +no_defs",
    3857: "+proj=merc +a=6378137 +b=6378137 +lat_ts=0.0 +lon_0=0.0 +x_0=0.0 "
    "+y_0=0 +k=1.0 +units=m +nadgrids=@null +wktext +no_defs",
}

# The PROJ 4 datum table (PROJ's pj_datums, proj4rs's datums.rs): the
# ellipsoid and Helmert each `+datum=` name stands for.
DATUMS = {
    "WGS84": "+ellps=WGS84 +towgs84=0,0,0",
    "NAD83": "+ellps=GRS80 +towgs84=0,0,0",
    "OSGB36": "+ellps=airy "
    "+towgs84=446.448,-125.157,542.060,0.1502,0.2470,0.8421,-20.4894",
}

GRID_COLS, GRID_ROWS = 5, 4  # 20 points a direction
INSET = 0.04  # keep off the area's very edges


def reference_string(code, proj):
    """The string pyproj is given: `+datum=` expanded; EPSG:3857 as itself."""
    if code == 3857:
        return "EPSG:3857"
    parts = []
    for p in proj.split():
        if p.startswith("+datum="):
            parts.append(DATUMS[p[len("+datum="):]])
        else:
            parts.append(p)
    return " ".join(parts) + " +type=crs"


def lattice(bounds, shift):
    """GRID_COLS x GRID_ROWS lon/lat points over `bounds` (w, s, e, n), the
    cells' centres moved by `shift` (a fraction of a cell) in both axes."""
    w, s, e, n = bounds
    dx, dy = (e - w) * (1 - 2 * INSET), (n - s) * (1 - 2 * INSET)
    w, s = w + (e - w) * INSET, s + (n - s) * INSET
    pts = []
    for j in range(GRID_ROWS):
        for i in range(GRID_COLS):
            pts.append(
                (
                    w + dx * (i + 0.5 + shift) / GRID_COLS,
                    s + dy * (j + 0.5 + shift) / GRID_ROWS,
                )
            )
    return pts


def area_of_use(code):
    a = CRS.from_epsg(code).area_of_use
    w, s, e, n = a.west, a.south, a.east, a.north
    if code == 3857:  # the whole world: keep to latitudes maps show
        s, n = -80.0, 80.0
    return [w, s, e, n]


def one_crs(code, proj):
    ref = reference_string(code, proj)
    to_wgs = Transformer.from_crs(CRS(ref), CRS(WGS84), always_xy=True)
    bounds = area_of_use(code)
    forward = []
    for lon, lat in lattice(bounds, 0.0):
        x, y = to_wgs.transform(lon, lat, direction="INVERSE")
        forward.append([lon, lat, x, y])
    inverse = []
    for lon, lat in lattice(bounds, 0.25):
        x, y = to_wgs.transform(lon, lat, direction="INVERSE")
        x, y = round(x, 1), round(y, 1)  # round inputs, independent of cota
        lon2, lat2 = to_wgs.transform(x, y)
        inverse.append([x, y, lon2, lat2])
    return {
        "code": code,
        "name": CRS.from_epsg(code).name,
        "proj_cota": proj,
        "proj_reference": ref,
        "operation": to_wgs.definition,
        "area_of_use": bounds,
        "forward": forward,
        "inverse": inverse,
    }


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = os.path.join(root, "crates/cota-io/tests/data/crs_reference.json")
    doc = {
        "generator": "tools/crs_reference.py",
        "pyproj": pyproj.__version__,
        "proj": pyproj.proj_version_str,
        "note": "forward: [lon, lat, x, y]; inverse: [x, y, lon, lat]; "
        "degrees (WGS 84) and metres",
        "crs": [one_crs(code, proj) for code, proj in CRSS.items()],
    }
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
