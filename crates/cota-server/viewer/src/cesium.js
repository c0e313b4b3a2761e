// The CesiumJS page: the server's quantized-mesh tiles (the tile set mounted
// at /tiles/: /tiles/layer.json, /tiles/{z}/{x}/{y}.terrain) in a stock
// CesiumJS viewer, served locally (no Ion token, nothing from the network),
// made readable for a person:
//  * the terrain lit by a light from the north-west (vertex normals
//    requested: the server's tiles carry them),
//  * draped with the server's shaded-relief imagery (/imagery.json,
//    /imagery/{z}/{x}/{y}.png: hillshade over a hypsometric tint made from
//    the DEM, geographic tiling, TMS rows),
//  * the data's footprint outlined, the zoom-out bounded, a short help.
// `?plain` shows the page as it was before (no light, no imagery, no
// normals): the browser test compares the two.
// window.cotaCesium reports tile loads and errors, and holds the terrain
// provider and viewer, for the browser tests.
const Cesium = window.Cesium;
const status = document.getElementById('status');
const help = document.getElementById('help');
const plain = new URLSearchParams(location.search).has('plain');
// `?3dtiles`: 3D Tiles terrain through CesiumJS's Cesium3DTilesTerrainProvider
// instead of the quantized-mesh tiles: the pyramid given to `cota serve
// --tiles` (a `cota tiles --format 3dtiles` directory or .3tz), or the one
// the server makes from its tiles' hierarchy on the first request.
const threeD = new URLSearchParams(location.search).has('3dtiles');
const report = { ready: false, tileErrors: 0, tilesLoaded: false, error: null, plain, imagery: false };
window.cotaCesium = report;

const sleep = (ms) => new Promise((ok) => setTimeout(ok, ms));

/** /health once the server has made (or given up on) its tiles and imagery. */
async function health() {
  for (;;) {
    const h = await (await fetch('/health')).json();
    if (h.tiles !== 'pending' && h.imagery !== 'pending') return h;
    status.textContent = 'the server is preparing its tiles…';
    await sleep(500);
  }
}

/** The direction a light from azimuth `az` (degrees from north) and `alt` degrees up travels at lon, lat. */
function lightAt(lon, lat, az = 315, alt = 45) {
  const [a, e] = [Cesium.Math.toRadians(az), Cesium.Math.toRadians(alt)];
  const toLight = new Cesium.Cartesian3(Math.sin(a) * Math.cos(e), Math.cos(a) * Math.cos(e), Math.sin(e));
  const enu = Cesium.Transforms.eastNorthUpToFixedFrame(Cesium.Cartesian3.fromDegrees(lon, lat));
  const d = Cesium.Matrix4.multiplyByPointAsVector(enu, toLight, new Cesium.Cartesian3());
  return Cesium.Cartesian3.normalize(Cesium.Cartesian3.negate(d, d), d);
}

function makeViewer(terrainProvider) {
  return new Cesium.Viewer('globe', {
    terrainProvider,
    baseLayer: false,
    baseLayerPicker: false,
    geocoder: false,
    homeButton: false,
    sceneModePicker: false,
    navigationHelpButton: false,
    animation: false,
    timeline: false,
    fullscreenButton: false,
    infoBox: false,
    selectionIndicator: false,
    skyBox: false,
    skyAtmosphere: false,
  });
}

/** Light, relief imagery, outline and zoom bounds over the data's bounds `b` (W, S, E, N degrees). */
function dress(viewer, b, imagery) {
  const [lon, lat] = [(b[0] + b[2]) / 2, (b[1] + b[3]) / 2];
  const globe = viewer.scene.globe;
  // Beyond the data: a slate grey, so the footprint stands out.
  globe.baseColor = Cesium.Color.fromCssColorString('#66707a');
  globe.enableLighting = true;
  globe.dynamicAtmosphereLighting = false;
  viewer.scene.light = new Cesium.DirectionalLight({ direction: lightAt(lon, lat), intensity: 2.2 });
  if (imagery) {
    // Bounds across the antimeridian (west > east) as two layers, one each
    // side of 180°: CesiumJS does not draw a provider's rectangle that
    // crosses it on its east side.
    const [w, s, e, n] = imagery.bounds;
    const parts = e < w ? [[w, s, 180, n], [-180, s, e, n]] : [[w, s, e, n]];
    for (const r of parts) {
      viewer.imageryLayers.addImageryProvider(new Cesium.UrlTemplateImageryProvider({
        url: '/imagery/{z}/{x}/{reverseY}.png',
        tilingScheme: new Cesium.GeographicTilingScheme(),
        rectangle: Cesium.Rectangle.fromDegrees(...r),
        minimumLevel: 0,
        maximumLevel: imagery.maxzoom,
        tileWidth: imagery.tileSize,
        tileHeight: imagery.tileSize,
        credit: 'shaded relief drawn by cota from the DEM',
      }));
    }
    report.imagery = true;
  }
  viewer.entities.add({
    polyline: {
      positions: Cesium.Cartesian3.fromDegreesArray([b[0], b[1], b[2], b[1], b[2], b[3], b[0], b[3], b[0], b[1]]),
      clampToGround: true,
      width: 2,
      material: Cesium.Color.fromCssColorString('#ffd54a'),
    },
  });
  const extent = extentM(b);
  const ctl = viewer.scene.screenSpaceCameraController;
  ctl.minimumZoomDistance = 50;
  ctl.maximumZoomDistance = Math.min(2e7, Math.max(2e5, 10 * extent));
  report.maxZoomDistance = ctl.maximumZoomDistance;
}

/** The diagonal of bounds `b` in metres. */
function extentM(b) {
  const g = new Cesium.EllipsoidGeodesic(Cesium.Cartographic.fromDegrees(b[0], b[1]), Cesium.Cartographic.fromDegrees(b[2], b[3]));
  return g.surfaceDistance;
}

/** An oblique view from the south over the middle of bounds `b`. */
function home(viewer, b) {
  const centre = Cesium.Cartesian3.fromDegrees((b[0] + b[2]) / 2, (b[1] + b[3]) / 2);
  viewer.camera.lookAt(centre, new Cesium.HeadingPitchRange(0, Cesium.Math.toRadians(-40), 0.6 * extentM(b)));
  viewer.camera.lookAtTransform(Cesium.Matrix4.IDENTITY);
}

/** Renders a frame and measures the canvas: luminance mean and spread over the middle half. */
report.pixels = () => {
  const v = report.viewer;
  v.scene.render();
  const src = v.scene.canvas;
  const cv = document.createElement('canvas');
  [cv.width, cv.height] = [src.width, src.height];
  const g = cv.getContext('2d');
  g.drawImage(src, 0, 0);
  const [x0, y0, w, h] = [src.width >> 2, src.height >> 2, src.width >> 1, src.height >> 1];
  const px = g.getImageData(x0, y0, w, h).data;
  let n = 0, sum = 0, sum2 = 0;
  for (let i = 0; i < px.length; i += 4) {
    const l = 0.2126 * px[i] + 0.7152 * px[i + 1] + 0.0722 * px[i + 2];
    n++;
    sum += l;
    sum2 += l * l;
  }
  const mean = sum / n;
  return { mean, std: Math.sqrt(Math.max(0, sum2 / n - mean * mean)), pixels: n };
};

async function main() {
  Cesium.Ion.defaultAccessToken = '';
  const h = await health();
  if (threeD && !['yes', 'on request'].includes(h.tiles3d)) throw new Error('this server has no 3D Tiles: run cota serve on a geographic DEM, or with --tiles DIR (or OUT.3tz) written by cota tiles --format 3dtiles');
  if (!threeD && h.tiles !== 'yes') throw new Error(`this server has no tiles (${h.tiles}): run cota serve on a geographic DEM, or with --tiles DIR`);
  const layer = h.tiles === 'yes' ? await (await fetch('/tiles/layer.json')).json() : {};
  const imagery = !plain && h.imagery === 'yes' ? await (await fetch('/imagery.json')).json() : null;
  const terrainProvider = threeD
    ? await Cesium.Cesium3DTilesTerrainProvider.fromUrl('/3dtiles/tileset.json', { requestVertexNormals: !plain })
    : await Cesium.CesiumTerrainProvider.fromUrl('/tiles/', { requestVertexNormals: !plain, requestWaterMask: false, requestMetadata: true });
  report.threeD = threeD;
  report.terrainProvider = terrainProvider;
  terrainProvider.errorEvent?.addEventListener((e) => {
    report.tileErrors++;
    report.lastError = String(e.message || e);
  });
  const viewer = makeViewer(terrainProvider);
  report.viewer = viewer;
  viewer.scene.globe.baseColor = Cesium.Color.fromCssColorString('#8aa37b');
  const given = (imagery && imagery.bounds) || layer.bounds || [-180, -90, 180, 90];
  // Across the antimeridian west > east; the page's centre, outline and
  // extent take east a turn further on.
  const b = given[2] < given[0] ? [given[0], given[1], given[2] + 360, given[3]] : given;
  report.bounds = given;
  if (plain) {
    viewer.scene.globe.enableLighting = false;
    viewer.camera.setView({ destination: Cesium.Rectangle.fromDegrees(given[0], given[1], given[2], given[3]) });
    help.hidden = true;
  } else {
    dress(viewer, b, imagery);
    home(viewer, b);
  }
  viewer.scene.globe.tileLoadProgressEvent.addEventListener((n) => {
    report.pending = n;
    if (n === 0) report.tilesLoaded = true;
    status.textContent = `${threeD ? '3D Tiles terrain' : 'quantized-mesh tiles'}${imagery ? ' and shaded relief' : ''} from this server\npending tiles ${n}  errors ${report.tileErrors}`;
  });
  document.addEventListener('keydown', (e) => {
    if (e.key === 'h' || e.key === 'H') help.hidden = !help.hidden;
    if (e.key === 'r' || e.key === 'R') home(viewer, b);
  });
  report.ready = true;
}

main().catch((e) => {
  report.error = String(e.message || e);
  status.textContent = `error: ${report.error}`;
  console.error(e);
});
