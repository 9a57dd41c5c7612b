// The page `scan2lod export --format 3dtiles` writes beside tileset.json:
// 3DTilesRendererJS on three.js, framed on the tileset's root bounding
// volume, with orbit controls and a readout of what is drawn and loaded.
// Bundled with everything it imports into one script at build time
// (delivery/CMakeLists.txt), so that the page loads nothing but its folder.
//
// The view can be given in the address, in the tileset's frame, as
// `scan2lod render --camera` takes it:
//   index.html?camera=EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV   (eye, target, up, vertical degrees)
//
// window.scan2lod is the hook tests drive the page by (tests/web/):
//   ready                           a promise, settled once the root tileset is in and framed
//   setCamera(eye, target, up, fov) in the tileset's frame (arrays of 3 numbers, degrees)
//   camera()                        the view now, in the same terms
//   stats()                         { tilesDrawn, trianglesDrawn, deepestDrawn, requested, loaded, failed, idle }
//   snapshot()                      the canvas as a PNG data URL, drawn just now
import {
  AmbientLight, Color, DirectionalLight, PerspectiveCamera, Scene, Sphere, Vector3, WebGLRenderer,
} from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { MeshoptDecoder } from 'three/addons/libs/meshopt_decoder.module.js';
import { TilesRenderer } from '3d-tiles-renderer/three';
import { GLTFExtensionsPlugin } from '3d-tiles-renderer/three/plugins';

// The view scan2lod's own pictures start from (visualize/scene.h): down -z
// with +y up, the bounding sphere filling the narrower side.
const kStartDirection = new Vector3(0, 0, 1);
const kStartUp = new Vector3(0, 1, 0);
const kFovDegrees = 30;

const canvasHolder = document.getElementById('view');
const readout = document.getElementById('readout');

const renderer = new WebGLRenderer({ antialias: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
canvasHolder.appendChild(renderer.domElement);

const scene = new Scene();
scene.background = new Color(0x20242c);
const camera = new PerspectiveCamera(kFovDegrees, window.innerWidth / window.innerHeight, 0.01, 100);
camera.up.copy(kStartUp);
// A light that moves with the camera, so that whatever faces the viewer is lit.
const headlight = new DirectionalLight(0xffffff, 1.6);
headlight.position.set(0.3, 0.5, 1);
camera.add(headlight);
scene.add(camera, new AmbientLight(0xffffff, 0.25));

let controls = orbitControls();

const tiles = new TilesRenderer(new URL('tileset.json', document.baseURI).href);
// scan2lod's tiles are EXT_meshopt_compression-compressed (delivery/tile_glb.h).
tiles.registerPlugin(new GLTFExtensionsPlugin({ meshoptDecoder: MeshoptDecoder }));
tiles.setCamera(camera);
tiles.setResolutionFromRenderer(camera, renderer);
scene.add(tiles.group);

const counts = { requested: 0, loaded: 0, failed: 0 };
// The tileset's centre in its own frame. The group is moved by minus it, so
// that a georeferenced tileset's large coordinates stay out of the floats.
const centre = new Vector3();
let radius = 1;
let framed = false;
let dirty = true;
let updatesSinceChange = 0;

tiles.addEventListener('tile-download-start', () => { counts.requested++; });
tiles.addEventListener('load-model', () => { counts.loaded++; dirty = true; });
tiles.addEventListener('tile-visibility-change', () => { dirty = true; });
tiles.addEventListener('needs-update', () => { dirty = true; });
tiles.addEventListener('load-error', (e) => {
  counts.failed++;
  console.error(`scan2lod viewer: could not load ${e.url}: ${e.error && e.error.message}`);
});

let settleReady;
let failReady;
const ready = new Promise((resolve, reject) => { settleReady = resolve; failReady = reject; });

// Near and far planes around the tileset's sphere, wherever the camera is.
function fitClippingPlanes() {
  const distance = camera.position.length();  // the sphere is at the origin
  camera.near = Math.max(distance - 1.5 * radius, 1e-3 * radius);
  camera.far = distance + 1.5 * radius;
  camera.updateProjectionMatrix();
}

function cameraChanged() {
  fitClippingPlanes();
  camera.updateMatrixWorld();
  dirty = true;
  updatesSinceChange = 0;
}

// Orbits about `controls.target` around camera.up. OrbitControls takes the
// up axis when it is made, so a new up needs new controls.
function orbitControls() {
  const c = new OrbitControls(camera, renderer.domElement);
  c.addEventListener('change', cameraChanged);
  return c;
}

function setCamera(eye, target, up, fovDegrees) {
  const orbitCentre = new Vector3().fromArray(target).sub(centre);
  camera.position.fromArray(eye).sub(centre);
  camera.up.fromArray(up).normalize();
  camera.fov = fovDegrees;
  camera.lookAt(orbitCentre);
  controls.dispose();
  controls = orbitControls();
  controls.target.copy(orbitCentre);
  controls.update();
  cameraChanged();
}

function currentCamera() {
  return {
    eye: camera.position.clone().add(centre).toArray(),
    target: controls.target.clone().add(centre).toArray(),
    up: camera.up.toArray(),
    fov: camera.fov,
  };
}

// ?camera=EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV, or null when absent. A malformed
// one is reported on the console and the tileset framed instead.
function cameraFromAddress() {
  const text = new URLSearchParams(window.location.search).get('camera');
  if (text === null) return null;
  const v = text.split(',').map(Number);
  if (v.length !== 10 || !v.every(Number.isFinite) || !(v[9] > 0 && v[9] < 180)) {
    console.error(`scan2lod viewer: camera=${text}: expected EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV ` +
                  '(eye, target, up, vertical field of view in degrees)');
    return null;
  }
  return { eye: v.slice(0, 3), target: v.slice(3, 6), up: v.slice(6, 9), fov: v[9] };
}

function frameTileset() {
  const sphere = new Sphere();
  if (!tiles.getBoundingSphere(sphere)) return false;
  centre.copy(sphere.center);
  radius = Math.max(sphere.radius, 1e-9);
  tiles.group.position.copy(centre).negate();
  tiles.group.updateMatrixWorld(true);
  const asked = cameraFromAddress();
  if (asked) {
    setCamera(asked.eye, asked.target, asked.up, asked.fov);
    return true;
  }
  const distance = radius / Math.sin((kFovDegrees / 2) * Math.PI / 180) / Math.min(1, camera.aspect);
  const eye = kStartDirection.clone().multiplyScalar(distance).add(centre);
  setCamera(eye.toArray(), centre.toArray(), kStartUp.toArray(), kFovDegrees);
  return true;
}

tiles.addEventListener('load-root-tileset', () => {
  framed = frameTileset();
  if (framed) settleReady();
  else failReady(new Error('tileset.json: the root tile has no bounding volume'));
});
tiles.addEventListener('load-error', (e) => {
  if (framed || e.tile !== null) return;
  readout.textContent = `could not load tileset.json: ${e.error && e.error.message}`;
  failReady(e.error);
});

function busy() {
  const s = tiles.stats;
  return tiles.isLoading || s.queued + s.downloading + s.parsing > 0;
}

function stats() {
  let deepest = -1;
  for (const tile of tiles.visibleTiles) deepest = Math.max(deepest, tile.internal.depth);
  return {
    tilesDrawn: tiles.visibleTiles.size,
    trianglesDrawn: renderer.info.render.triangles,
    deepestDrawn: deepest,
    requested: counts.requested,
    loaded: counts.loaded,
    failed: counts.failed,
    // Settled: the tiles the current view wants are in, and drawn.
    idle: framed && updatesSinceChange >= 2 && !busy() && !dirty,
  };
}

function showReadout() {
  const s = stats();
  readout.textContent = `${s.tilesDrawn} tiles drawn · ${s.trianglesDrawn.toLocaleString('en')} triangles · ` +
    `${s.loaded} of ${s.requested} tiles loaded` + (s.failed ? ` · ${s.failed} failed` : '');
}

function draw() {
  renderer.render(scene, camera);
  dirty = false;
  showReadout();
}

function snapshot() {
  tiles.update();
  draw();
  // Read in the same task as the draw: the drawing buffer is not kept.
  return renderer.domElement.toDataURL('image/png');
}

window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  renderer.setSize(window.innerWidth, window.innerHeight);
  tiles.setResolutionFromRenderer(camera, renderer);
  cameraChanged();
});

// Each frame: refine (cheap when nothing changed), and draw only when
// something did, which keeps a software-rendered page idle when at rest.
function frame() {
  controls.update();
  tiles.update();
  updatesSinceChange++;
  if (dirty) draw();
  requestAnimationFrame(frame);
}
requestAnimationFrame(frame);

window.scan2lod = { ready, setCamera, camera: currentCamera, stats, snapshot };
