// hapto view: draws the scene with three.js and follows a live session (/stream, Server-Sent
// Events) or plays a recording (/trace.json). Read-only: it only ever GETs.
'use strict';

const COLORS = [0x4fc3f7, 0xffb74d, 0xba68c8, 0x81c784, 0xf06292, 0xfff176];
const OBJECT_COLOR = 0x8a96a8, CONTACT_COLOR = 0xff7043, MOVING_COLOR = 0x66bb6a;
const LISTED_COLOR = 0xd4c15a; // in a shown cursor leaf
const HISTORY = 300; // chart samples (10 s at 30 Hz)

const view = { objects: new Map(), devices: [], frames: 0, listed: new Set() };

function v3(a) { return new THREE.Vector3(a[0], a[1], a[2]); }

function setupScene(scene) {
  const host = document.getElementById('scene');
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(host.clientWidth, host.clientHeight);
  renderer.setClearColor(0x20242b);
  host.appendChild(renderer.domElement);

  const world = new THREE.Scene();
  world.add(new THREE.AmbientLight(0xffffff, 0.45));
  const sun = new THREE.DirectionalLight(0xffffff, 0.8);
  sun.position.set(1, 2, 1.5);
  world.add(sun);

  // A trace records no cursor leaves and no candidates: the player offers and shows neither.
  view.live = scene.mode !== 'trace';
  document.getElementById('leavesOption').hidden = !view.live;
  const lo = v3(scene.bounds.min), hi = v3(scene.bounds.max);
  const centre = lo.clone().add(hi).multiplyScalar(0.5);
  const size = hi.clone().sub(lo).length();
  view.size = size;
  const camera = new THREE.PerspectiveCamera(45, host.clientWidth / host.clientHeight,
                                            size / 1000, size * 100);
  camera.position.copy(centre).add(new THREE.Vector3(0.6, 0.5, 1.0).multiplyScalar(size));
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();

  const bounds = new THREE.Box3Helper(new THREE.Box3(lo, hi), 0x555c66);
  world.add(bounds);
  for (const o of scene.objects) {
    const mesh = makeObject(o);
    if (mesh) { addGhost(mesh); world.add(mesh); view.objects.set(o.id, mesh); }
  }
  scene.devices.forEach((d, i) => view.devices.push(makeDevice(world, d, i)));
  // Past the page's triangle cap a mesh comes simplified (or, with no room left, as its box).
  const simplified = (scene.meshes && scene.meshes.simplified) || [];
  const boxed = (scene.meshes && scene.meshes.boxed) || [];
  if (simplified.length || boxed.length) {
    const byId = new Map(scene.objects.map((o) => [o.id, o]));
    const lines = simplified.map((id) => 'mesh #' + id + ' drawn simplified, ' +
      byId.get(id).trianglesShown + ' of its ' + byId.get(id).triangleCount + ' triangles');
    if (boxed.length) lines.push('mesh #' + boxed.join(', #') + ' drawn as its bounding box');
    const note = document.getElementById('meshnote');
    note.textContent = lines.join('; ') + ' (the page takes ' + scene.meshes.maxTriangles +
      ' triangles per scene)';
    note.dataset.simplified = simplified.join(',');
    note.dataset.boxed = boxed.join(',');
    note.style.display = 'block';
  }

  // Drawn on demand ("rendering on demand" in the three.js manual): when a frame arrives, the
  // camera moves or the window changes size, at most once per display frame, so a page whose
  // session has ended or whose player is paused draws nothing. While frames stream in (30 a
  // second) it costs about what drawing every display frame did: headless Chromium with
  // software WebGL kept 1.87 of the two cores busy either way.
  let pending = false;
  view.redraw = () => {
    if (pending) return;
    pending = true;
    requestAnimationFrame(() => { pending = false; renderer.render(world, camera); });
  };
  controls.addEventListener('change', view.redraw);
  window.addEventListener('resize', () => {
    camera.aspect = host.clientWidth / host.clientHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(host.clientWidth, host.clientHeight);
    view.redraw();
  });
  view.redraw();
}

function makeObject(o) {
  let geometry;
  if (o.shape === 'box') {
    geometry = new THREE.BoxBufferGeometry(2 * o.halfExtents[0], 2 * o.halfExtents[1],
                                           2 * o.halfExtents[2]);
  } else if (o.shape === 'sphere') {
    geometry = new THREE.SphereBufferGeometry(o.halfExtents[0], 24, 16);
  } else if (o.shape === 'mesh' && o.vertices && o.triangles) {
    // Vertices x y z ... and triangles a b c ... (flat) in the object's frame, placed by
    // centre and rotation like the other shapes, so a carried mesh moves with its pose.
    geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.Float32BufferAttribute(o.vertices.flat(), 3));
    geometry.setIndex(o.triangles.flat());
    geometry.computeVertexNormals();
  } else if (o.shape === 'mesh' && o.localBounds) {
    // No room left under the page's triangle cap: its bounding box in its own frame, as a
    // wireframe.
    const lo = v3(o.localBounds.min), hi = v3(o.localBounds.max);
    const size = hi.clone().sub(lo), mid = lo.clone().add(hi).multiplyScalar(0.5);
    const box = new THREE.BoxBufferGeometry(size.x, size.y, size.z);
    box.translate(mid.x, mid.y, mid.z);
    const wire = new THREE.LineSegments(new THREE.EdgesGeometry(box),
                                        new THREE.LineBasicMaterial({ color: OBJECT_COLOR }));
    placeObject(wire, o.center, o.rotation);
    return wire;
  } else {
    return null;
  }
  const mesh = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ color: OBJECT_COLOR }));
  placeObject(mesh, o.center, o.rotation);
  return mesh;
}

// An object's ghost: the same geometry, unlit and half transparent, drawn without the depth
// test after every solid object (three.js draws transparent objects after opaque ones; the
// hands' markers, transparent at full opacity with renderOrder 1, come after the ghosts). A
// child of the object, so it follows its pose; shown while the object is highlighted.
function addGhost(object) {
  const options = { transparent: true, opacity: 0.5, depthTest: false, depthWrite: false };
  const ghost = object.isMesh
    ? new THREE.Mesh(object.geometry, new THREE.MeshBasicMaterial(options))
    : new THREE.LineSegments(object.geometry, new THREE.LineBasicMaterial(options));
  ghost.visible = false;
  ghost.renderOrder = 0.5;
  object.add(ghost);
  object.userData.ghost = ghost;
}

function placeObject(mesh, centre, q) {
  mesh.position.set(centre[0], centre[1], centre[2]);
  mesh.quaternion.set(q[1], q[2], q[3], q[0]); // ours is (w, x, y, z)
}

function makeDevice(world, d, i) {
  const color = COLORS[i % COLORS.length];
  const r = view.size * 0.012;
  const point = new THREE.Mesh(new THREE.SphereBufferGeometry(r, 16, 12),
                               new THREE.MeshBasicMaterial({ color }));
  const proxy = new THREE.Mesh(new THREE.SphereBufferGeometry(r, 12, 8),
                               new THREE.MeshBasicMaterial({ color, wireframe: true }));
  const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 1, 0), new THREE.Vector3(), r, color);
  // The device point's cursor leaf: the paper's idea made visible (the box the cursor caches
  // and the objects it hands to the renderer); shown when "leaves" is ticked.
  const leaf = new THREE.Box3Helper(new THREE.Box3(), color);
  // Drawn over the objects and their ghosts, never hidden by them: a hand works among the
  // objects (the default scene's hands are inside a block of 200 cubes), where a depth-tested
  // marker is out of sight from every side. Transparent at full opacity only to be drawn in
  // three.js's second (transparent) list, after the ghosts.
  for (const o of [point, proxy, arrow, leaf]) {
    o.visible = false;
    o.traverse((part) => {
      part.renderOrder = 1;
      if (part.material) {
        part.material.depthTest = false;
        part.material.transparent = true;
      }
    });
    world.add(o);
  }
  const row = document.createElement('div');
  row.className = 'device';
  row.dataset.device = d.name;
  row.innerHTML =
    '<span class="name"></span> <span data-field="verdict"></span>' +
    ' <span data-field="why" class="why"></span><br>' +
    '|F| <span data-field="forceN">-</span> N &middot; ticks <span data-field="ticks">0</span>' +
    ' &middot; misses <span data-field="misses">0</span><br>' +
    'load p50 <span data-field="loadP50">-</span> % &middot; p99.9 ' +
    '<span data-field="loadP999">-</span> %' +
    (view.live ? ' &middot; candidates/tick <span data-field="candidates">-</span>' : '') +
    ' <span data-field="contacts"></span>' +
    (view.live ? '<br><span data-field="leaf"></span>' : '') +
    '<canvas width="254" height="56"></canvas>';
  row.querySelector('.name').textContent = d.name;
  row.querySelector('.name').style.color = '#' + color.toString(16).padStart(6, '0');
  document.getElementById('devices').appendChild(row);
  return { name: d.name, point, proxy, arrow, leaf, row, chart: row.querySelector('canvas'),
           history: [] };
}

function field(dev, name, text) { dev.row.querySelector('[data-field="' + name + '"]').textContent = text; }

// One device's state, from a live frame or a trace frame.
function showDevice(dev, f, touched) {
  if (f.point) {
    const p = v3(f.point);
    dev.point.position.copy(p);
    dev.point.visible = true;
    const proxy = f.proxy ? v3(f.proxy) : p;
    dev.proxy.position.copy(proxy);
    dev.proxy.visible = !!f.proxy;
    const force = v3(f.force);
    const n = force.length();
    // Scaled: a tenth of the scene's diagonal per 2 N.
    const length = n * view.size * 0.05;
    dev.arrow.visible = n > 1e-6;
    if (dev.arrow.visible) {
      dev.arrow.position.copy(proxy);
      dev.arrow.setDirection(force.clone().normalize());
      dev.arrow.setLength(length, Math.min(length * 0.3, view.size * 0.02), view.size * 0.01);
    }
    field(dev, 'forceN', n.toFixed(2));
    for (const id of f.contacts || []) touched.add(id);
    field(dev, 'contacts', (f.contacts || []).length ? 'touching #' + f.contacts.join(', #') : '');
  }
  if (dev.row.dataset.firstTicks === undefined) {
    dev.row.dataset.firstTicks = String(f.ticks); // what the page first showed, for its test
  }
  field(dev, 'ticks', String(f.ticks));
  field(dev, 'misses', String(f.misses));
  field(dev, 'loadP50', (100 * f.loadP50).toFixed(2));
  field(dev, 'loadP999', (100 * f.loadP999).toFixed(2));
  if (view.live) {
    if (f.candidates !== undefined) field(dev, 'candidates', f.candidates.toFixed(1));
    showLeaf(dev, f);
  }
  if (f.verdict !== undefined) {
    const v = dev.row.querySelector('[data-field="verdict"]');
    v.textContent = f.verdict;
    v.className = f.verdict === 'stable' ? 'stable' : f.verdict.startsWith('FAULT') ? 'fault' : 'unstable';
    // Unstable by late wake-ups while the ticks stayed short (the run report's note, whole
    // on hover): the machine's scheduling, not the tick.
    const why = dev.row.querySelector('[data-field="why"]');
    why.textContent = f.note ? 'late wake-ups' : '';
    why.title = f.note || '';
  }
}

// The cursor leaf's box and what it lists (live only; a trace records no leaves).
function showLeaf(dev, f) {
  const on = document.getElementById('leaves').checked;
  dev.leaf.visible = on && !!f.leaf;
  if (f.leaf) {
    dev.leaf.box.set(v3(f.leaf.min), v3(f.leaf.max));
    field(dev, 'leaf', 'leaf: ' + f.leaf.items + ' items' +
          (f.leaf.objects.length ? ' (#' + f.leaf.objects.join(', #') + ')' : ''));
    if (on) for (const id of f.leaf.objects) view.listed.add(id);
  } else {
    field(dev, 'leaf', f.ticks !== undefined && f.point ? 'leaf: outside the bounds' : '');
  }
}

function chart(dev, f) {
  dev.history.push([f.loadP50, f.loadP999, f.misses]);
  if (dev.history.length > HISTORY) dev.history.shift();
  const c = dev.chart, g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  const top = Math.max(1.0, ...dev.history.map(h => h[1]));
  const y = v => c.height - 2 - (c.height - 12) * v / top;
  g.strokeStyle = '#555'; g.beginPath(); g.moveTo(0, y(1)); g.lineTo(c.width, y(1)); g.stroke();
  [['#4fc3f7', 0], ['#ff8a80', 1]].forEach(([color, k]) => {
    g.strokeStyle = color; g.beginPath();
    dev.history.forEach((h, i) => {
      const x = c.width * i / (HISTORY - 1);
      if (i === 0) g.moveTo(x, y(h[k])); else g.lineTo(x, y(h[k]));
    });
    g.stroke();
  });
  const first = dev.history[0][2], last = dev.history[dev.history.length - 1][2];
  g.fillStyle = '#ccc';
  g.fillText('load p50 / p99.9 (100 % line), misses +' + (last - first) + ' in view', 4, 10);
}

function showFrame(frame, devices) {
  const touched = new Set();
  view.listed = new Set();
  devices.forEach((f, i) => { if (view.devices[i]) { showDevice(view.devices[i], f, touched); chart(view.devices[i], f); } });
  const moving = new Set();
  for (const p of frame.poses || []) {
    const mesh = view.objects.get(p.id);
    if (mesh) placeObject(mesh, p.center, p.rotation);
    if (p.moving) moving.add(p.id);
  }
  for (const [id, mesh] of view.objects) {
    const highlight = touched.has(id) ? CONTACT_COLOR : moving.has(id) ? MOVING_COLOR
                    : view.listed.has(id) ? LISTED_COLOR : null;
    mesh.material.color.setHex(highlight === null ? OBJECT_COLOR : highlight);
    // An object in a highlight colour also shows through whatever hides it, as its ghost:
    // what a hand touches or its leaf lists is among the objects around it (inside the
    // default scene's block), and a touched floor must not hide what stands on it.
    const ghost = mesh.userData.ghost;
    ghost.visible = highlight !== null;
    if (ghost.visible) ghost.material.color.setHex(highlight);
  }
  view.frames++;
  if (view.redraw) view.redraw();
  const status = document.getElementById('status');
  status.dataset.frames = String(view.frames);
  if (status.dataset.firstT === undefined) status.dataset.firstT = String(frame.t);
  status.dataset.t = String(frame.t);
}

function followLive() {
  const status = document.getElementById('status');
  const source = new EventSource('/stream');
  source.onopen = () => { status.textContent = 'live'; };
  // The stream ends with the session; EventSource keeps trying to reconnect.
  source.onerror = () => { status.textContent = view.frames ? 'stream closed' : 'connecting'; };
  source.onmessage = (e) => { const frame = JSON.parse(e.data); showFrame(frame, frame.devices); };
}

// The recording: each device's frames by time; the newest at or before t is shown.
function playTrace(trace) {
  document.getElementById('player').style.display = 'block';
  document.getElementById('status').textContent = 'recorded';
  const slider = document.getElementById('slider'), button = document.getElementById('play');
  const clock = document.getElementById('clock');
  const duration = Math.max(trace.durationS, 1e-3);
  let t = 0, playing = true, last = performance.now();
  const at = (frames, time) => {
    let lo = 0, hi = frames.length - 1;
    while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (frames[mid].t <= time) lo = mid; else hi = mid - 1; }
    return frames[lo];
  };
  const show = () => {
    const devices = trace.devices.map(d => d.frames.length ? at(d.frames, t) : { ticks: 0, misses: 0, loadP50: 0, loadP999: 0 });
    // The dynamic bodies (bodies.trace): each at its newest pose at or before t.
    const poses = (trace.bodies || []).filter(b => b.frames.length).map(b => {
      const f = at(b.frames, t);
      return { id: b.id, center: f.center, rotation: f.rotation, moving: true };
    });
    showFrame({ t, poses }, devices);
    slider.value = String(Math.round(1000 * t / duration));
    clock.textContent = t.toFixed(2) + ' s';
    clock.dataset.t = String(t);
  };
  button.onclick = () => { playing = !playing; button.textContent = playing ? 'pause' : 'play'; last = performance.now(); };
  slider.oninput = () => { t = duration * Number(slider.value) / 1000; show(); };
  setInterval(() => {
    const now = performance.now();
    if (playing) { t += (now - last) / 1000; if (t > duration) t = 0; show(); }
    last = now;
  }, 1000 / 30);
  show();
}

fetch('/scene.json').then(r => r.json()).then(scene => {
  setupScene(scene);
  if (scene.mode === 'trace') {
    fetch('/trace.json').then(r => r.json()).then(playTrace);
  } else {
    followLive();
  }
});
