// CesiumJS on a scan2lod tileset with nothing but the served folder: no Cesium
// ion token, no imagery, terrain, globe, sky, sun or moon, so that the only
// requests are Cesium's own files and the tileset's. The tileset stays where
// its frame puts it (the bunny's frame is at the Earth's centre, which no
// globe hides here).
//
// window.cesiumTest is what tests/web/cesium_viewer.mjs drives:
//   ready                            a promise, settled when the tileset is added
//   setCamera(eye, target, up, fov)  in the tileset's frame, fov vertical (degrees)
//   stats()                          { selected, triangles, loaded, requested, failed, idle }
//   snapshot()                       the canvas as a PNG data URL, drawn just now
/* global Cesium */
const widget = new Cesium.CesiumWidget('view', {
  globe: false,
  skyBox: false,
  skyAtmosphere: false,
  baseLayer: false,
  shadows: false,
  useBrowserRecommendedResolution: true,
  msaaSamples: 1,
});
const scene = widget.scene;
// A saturated background no grey shade of the model comes near.
scene.backgroundColor = Cesium.Color.BLUE;
scene.fog.enabled = false;
// A light from the camera, as in scan2lod's own page.
scene.light = new Cesium.DirectionalLight({ direction: scene.camera.directionWC });
scene.preRender.addEventListener(() => { scene.light.direction = Cesium.Cartesian3.clone(scene.camera.directionWC); });

const counts = { loaded: 0, failed: 0 };
let tileset = null;
let framesSinceChange = 0;
scene.postRender.addEventListener(() => { framesSinceChange++; });

const ready = Cesium.Cesium3DTileset.fromUrl('tileset/tileset.json').then((t) => {
  tileset = t;
  t.tileLoad.addEventListener(() => { counts.loaded++; });
  t.tileFailed.addEventListener((e) => {
    counts.failed++;
    console.error(`cesium page: tile ${e.url} failed: ${e.message}`);
  });
  scene.primitives.add(t);
});

function setCamera(eye, target, up, fovDegrees) {
  const position = Cesium.Cartesian3.fromArray(eye);
  const direction = Cesium.Cartesian3.normalize(
    Cesium.Cartesian3.subtract(Cesium.Cartesian3.fromArray(target), position, new Cesium.Cartesian3()),
    new Cesium.Cartesian3());
  // Up made perpendicular to the view, as VTK and three.js make it.
  const right = Cesium.Cartesian3.normalize(
    Cesium.Cartesian3.cross(direction, Cesium.Cartesian3.fromArray(up), new Cesium.Cartesian3()),
    new Cesium.Cartesian3());
  const trueUp = Cesium.Cartesian3.cross(right, direction, new Cesium.Cartesian3());
  const camera = scene.camera;
  camera.setView({ destination: position, orientation: { direction, up: trueUp } });
  // Cesium's fov is the horizontal one on a wide canvas.
  const aspect = scene.canvas.clientWidth / scene.canvas.clientHeight;
  const half = (fovDegrees / 2) * Math.PI / 180;
  camera.frustum.fov = aspect > 1 ? 2 * Math.atan(Math.tan(half) * aspect) : 2 * half;
  framesSinceChange = 0;
}

function stats() {
  const s = tileset ? tileset.statistics : null;
  const settled = tileset !== null && tileset.tilesLoaded && s.numberOfPendingRequests === 0 &&
                  s.numberOfTilesProcessing === 0;
  return {
    selected: s ? s.selected : 0,
    triangles: s ? s.numberOfTrianglesSelected : 0,
    loaded: counts.loaded,
    requested: s ? s.numberOfLoadedTilesTotal + s.numberOfPendingRequests : 0,
    failed: counts.failed,
    idle: settled && framesSinceChange >= 3,
  };
}

function snapshot() {
  widget.render();
  return scene.canvas.toDataURL('image/png');
}

window.cesiumTest = { ready, setCamera, stats, snapshot };
