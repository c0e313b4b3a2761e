// The CesiumJS page: the server's quantized-mesh tiles (the tile set mounted
// at /tiles/: /tiles/layer.json, /tiles/{z}/{x}/{y}.terrain) in a stock
// CesiumJS viewer, served locally (no Ion token, no imagery from the
// network). window.cotaCesium reports tile loads and errors, and holds the
// terrain provider, for the browser test.
const Cesium = window.Cesium;
const status = document.getElementById('status');
const report = { ready: false, tileErrors: 0, tilesLoaded: false, error: null };
window.cotaCesium = report;

async function main() {
  Cesium.Ion.defaultAccessToken = '';
  const layer = await (await fetch('/tiles/layer.json')).json();
  const terrainProvider = await Cesium.CesiumTerrainProvider.fromUrl('/tiles/', { requestVertexNormals: false, requestWaterMask: false });
  report.terrainProvider = terrainProvider;
  terrainProvider.errorEvent.addEventListener((e) => {
    report.tileErrors++;
    report.lastError = String(e.message || e);
  });
  const viewer = new Cesium.Viewer('globe', {
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
  viewer.scene.globe.baseColor = Cesium.Color.fromCssColorString('#8aa37b');
  viewer.scene.globe.enableLighting = false;
  const b = layer.bounds || [-180, -90, 180, 90];
  viewer.camera.setView({ destination: Cesium.Rectangle.fromDegrees(b[0], b[1], b[2], b[3]) });
  viewer.scene.globe.tileLoadProgressEvent.addEventListener((n) => {
    report.pending = n;
    if (n === 0) report.tilesLoaded = true;
    status.textContent = `quantized-mesh tiles from this server\npending tiles ${n}  errors ${report.tileErrors}`;
  });
  report.ready = true;
  report.viewer = viewer;
}

main().catch((e) => {
  report.error = String(e.message || e);
  status.textContent = `error: ${report.error}`;
  console.error(e);
});
