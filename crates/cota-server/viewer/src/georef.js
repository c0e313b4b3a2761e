// Ground size of a stream's cells, from the georeference in its head: what
// cota-server's meta.json calls `cell_size_m` (cota-core's
// `Georef::pixel_size_m_at` at the grid's centre), for tools that read a
// `.cstream` without the server (bench/refine.mjs).

/** WGS 84 semi-major axis (m) and first eccentricity squared. */
const WGS84_A = 6378137.0;
const WGS84_E2 = 6.6943799901413e-3;

/** Metres per degree of longitude and of latitude at `latDeg` on WGS 84. */
export function metresPerDegree(latDeg) {
  const phi = (Math.max(-90, Math.min(90, latDeg)) * Math.PI) / 180;
  const s2 = Math.sin(phi) ** 2;
  const w = Math.sqrt(1 - WGS84_E2 * s2);
  const deg = Math.PI / 180;
  return [(WGS84_A / w) * Math.cos(phi) * deg, ((WGS84_A * (1 - WGS84_E2)) / (w * w * w)) * deg];
}

/** Whether a parsed stream CRS is geographic (lon/lat degrees), as cota-core decides. */
export function isGeographic(crs) {
  if (!crs) return false;
  if (crs.epsg !== undefined) return crs.epsg >= 4000 && crs.epsg < 5000;
  if (crs.geographic !== undefined) return true;
  return false;
}

/**
 * Cell size in metres [x, y] at the grid's centre for a georeference parsed by
 * `StreamReader` (`georef`), `w` × `h` samples. An unreferenced grid has unit
 * cells (as the server treats it); a projected CRS has its own units taken as
 * metres; Web Mercator is scaled by cos(latitude).
 */
export function cellSizeM(georef, w, h) {
  const px = Math.abs(georef.pixelX), py = Math.abs(georef.pixelY);
  if (!georef.known) return [px, py];
  const half = georef.pixelIsPoint ? 0 : 0.5;
  const y = georef.originY + ((h - 1) / 2 + half) * georef.pixelY;
  if (isGeographic(georef.crs)) {
    const [mx, my] = metresPerDegree(y);
    return [px * mx, py * my];
  }
  if (georef.crs && [3857, 900913, 3785].includes(georef.crs.epsg)) {
    const lat = 2 * Math.atan(Math.exp(y / WGS84_A)) - Math.PI / 2;
    return [px * Math.cos(lat), py * Math.cos(lat)];
  }
  return [px, py];
}
