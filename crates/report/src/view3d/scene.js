// The report's 3-D view: the best and the worst tool's episodes side by side under one time
// slider. The page's data (#view3d-data) gives, per output time, each joint's link point and axis,
// the flange frame and the tip, all computed by toolconf from the model's own kinematics; this
// script only draws them. A fragment #t=F (0 <= F <= 1) shows that fraction of the episode,
// paused and moved to the page's top (what the headless-browser test screenshots). Z is up, as in the robot's base frame.
const status = document.getElementById('view3d-status');
const fail = (e) => {
  status.textContent = '3-D view: error: ' + ((e && e.message) || e);
  status.dataset.state = 'error';
  console.error('view3d: ' + ((e && e.stack) || e));
};
try {
  start();
} catch (e) {
  fail(e);
}

function start() {
  const data = JSON.parse(document.getElementById('view3d-data').textContent);
  const canvas = document.getElementById('view3d-canvas');
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setScissorTest(true);
  const colours = [0x1f5fc8, 0xc81e1e];
  const panes = data.episodes.map((ep, k) => pane(ep, colours[k], data.goal, canvas.width / data.episodes.length / canvas.height));
  data.episodes.forEach((ep, k) => {
    document.getElementById('view3d-label-' + k).textContent = ep.label;
  });
  const t = data.episodes[0].t;
  const frames = Math.min(...data.episodes.map((ep) => ep.t.length));
  const slider = document.getElementById('view3d-slider');
  const play = document.getElementById('view3d-play');
  const clock = document.getElementById('view3d-time');
  slider.max = String(frames - 1);
  let frame = 0;
  let playing = true;
  let last = null;
  const fragment = /(?:^#|&)t=([0-9.]+)/.exec(location.hash);
  if (fragment) {
    const f = Math.min(1, Math.max(0, parseFloat(fragment[1]) || 0));
    frame = Math.round(f * (frames - 1));
    playing = false;
    // Headless screenshots show the page's top: bring the view there.
    document.body.prepend(document.getElementById('view3d'));
  }
  const draw = () => {
    const w = canvas.width / panes.length;
    panes.forEach((p, k) => {
      renderer.setViewport(k * w, 0, w, canvas.height);
      renderer.setScissor(k * w, 0, w, canvas.height);
      renderer.render(p.scene, p.camera);
    });
  };
  const show = (f) => {
    frame = f;
    slider.value = String(f);
    panes.forEach((p) => p.pose(f));
    clock.textContent = 't = ' + t[f].toFixed(2) + ' s';
    draw();
  };
  const label = () => {
    play.textContent = playing ? 'pause' : 'play';
  };
  slider.addEventListener('input', () => {
    playing = false;
    label();
    show(Number(slider.value));
  });
  play.addEventListener('click', () => {
    playing = !playing;
    if (playing && frame >= frames - 1) show(0);
    label();
  });
  // Real time: one output step of the episode per (t[1] - t[0]) seconds.
  const step = 1000 * Math.max(1e-3, frames > 1 ? t[1] - t[0] : 1);
  const tick = (now) => {
    if (!playing) {
      last = null;
    } else if (last === null) {
      last = now;
    } else if (now - last >= step) {
      last = now;
      if (frame + 1 >= frames) {
        playing = false;
        label();
      } else {
        show(frame + 1);
      }
    }
    requestAnimationFrame(tick);
  };
  label();
  show(frame);
  requestAnimationFrame(tick);
  status.textContent = '3-D view: ' + frames + ' frames, showing frame ' + frame;
  status.dataset.state = 'ready';
}

/// One episode's scene: the arm as capsules between its link points, a cylinder per joint along
/// its axis, the tool (its inertia box, a shaft to the tip, the tip) fixed to the flange, the
/// goal, and the tip's trail up to the frame shown.
function pane(ep, colour, goal, aspect) {
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf6f7f9);
  scene.add(new THREE.AmbientLight(0xffffff, 0.9));
  const sun = new THREE.DirectionalLight(0xffffff, 2.0);
  sun.position.set(2, -3, 4);
  scene.add(sun);
  const grid = new THREE.GridHelper(2, 20, 0xb8bcc2, 0xdde0e4);
  grid.rotation.x = Math.PI / 2;
  scene.add(grid);
  const material = (c) => new THREE.MeshStandardMaterial({ color: c, roughness: 0.55 });
  const [shell, joint, toolColour] = [material(0xd3d7dc), material(0x4d535b), material(colour)];
  const n = ep.joints;
  const s = ep.stride;
  const F = ep.frames;
  const at = (f, i) => new THREE.Vector3(F[f * s + i], F[f * s + i + 1], F[f * s + i + 2]);
  const base = new THREE.Mesh(new THREE.CylinderGeometry(0.1, 0.1, 0.04, 32), joint);
  base.rotation.x = Math.PI / 2;
  base.position.z = 0.02;
  scene.add(base);
  const links = [];
  for (let j = 0; j <= n; j++) links.push(capsule(scene, 0.04, shell));
  const joints = [];
  for (let j = 0; j < n; j++) {
    const m = new THREE.Mesh(new THREE.CylinderGeometry(0.05, 0.05, 0.11, 24), joint);
    scene.add(m);
    joints.push(m);
  }
  const tool = new THREE.Group();
  tool.matrixAutoUpdate = false;
  scene.add(tool);
  if (ep.box) {
    const b = ep.box;
    const box = new THREE.Mesh(new THREE.BoxGeometry(...b.sides.map((v) => Math.max(v, 0.004))), toolColour);
    box.matrixAutoUpdate = false;
    const a = (k) => new THREE.Vector3(b.axes[3 * k], b.axes[3 * k + 1], b.axes[3 * k + 2]);
    box.matrix.makeBasis(a(0), a(1), a(2)).setPosition(...b.centre);
    tool.add(box);
  }
  const tipOffset = new THREE.Vector3(...ep.tip_offset);
  capsule(tool, 0.006, toolColour).set(new THREE.Vector3(), tipOffset);
  const tip = new THREE.Mesh(new THREE.SphereGeometry(0.015, 20, 12), material(0x111111));
  tip.position.copy(tipOffset);
  tool.add(tip);
  const frames = ep.t.length;
  const tipAt = 6 * n + 12;
  const path = new Float32Array(3 * frames);
  const box3 = new THREE.Box3();
  for (let f = 0; f < frames; f++) {
    at(f, tipAt).toArray(path, 3 * f);
    box3.expandByPoint(at(f, tipAt));
  }
  for (let j = 0; j < n; j++) box3.expandByPoint(at(0, 6 * j));
  box3.expandByPoint(new THREE.Vector3());
  const line = (opacity) => {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(path, 3));
    const m = new THREE.LineBasicMaterial({ color: colour, transparent: opacity < 1, opacity });
    const l = new THREE.Line(g, m);
    scene.add(l);
    return l;
  };
  line(0.25);
  const trail = line(1);
  if (goal) {
    const g = new THREE.Mesh(new THREE.SphereGeometry(0.02, 24, 16), material(0x2a9d3a));
    g.position.set(...goal);
    scene.add(g);
    box3.expandByPoint(g.position);
  }
  const camera = new THREE.PerspectiveCamera(38, aspect, 0.01, 20);
  camera.up.set(0, 0, 1);
  const centre = box3.getCenter(new THREE.Vector3());
  const radius = Math.max(0.3, box3.getSize(new THREE.Vector3()).length() / 2);
  const distance = (1.35 * radius) / Math.sin((camera.fov * Math.PI) / 360);
  camera.position.copy(centre).add(new THREE.Vector3(1.3, -1.9, 0.8).normalize().multiplyScalar(distance));
  camera.lookAt(centre);
  const y = new THREE.Vector3(0, 1, 0);
  const pose = (f) => {
    let before = new THREE.Vector3();
    for (let j = 0; j < n; j++) {
      const p = at(f, 6 * j);
      links[j].set(before, p);
      joints[j].position.copy(p);
      const d = at(f, 6 * j + 3);
      joints[j].visible = d.lengthSq() > 0.5;
      if (joints[j].visible) joints[j].quaternion.setFromUnitVectors(y, d.normalize());
      before = p;
    }
    const flange = at(f, 6 * n);
    links[n].set(before, flange);
    tool.matrix.makeBasis(at(f, 6 * n + 3), at(f, 6 * n + 6), at(f, 6 * n + 9)).setPosition(flange);
    trail.geometry.setDrawRange(0, f + 1);
  };
  return { scene, camera, pose };
}

/// A capsule of `radius` between two points (a cylinder and two spheres), added to `parent`.
function capsule(parent, radius, material) {
  const rod = new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, 1, 20, 1, true), material);
  const ends = [0, 1].map(() => new THREE.Mesh(new THREE.SphereGeometry(radius, 20, 12), material));
  parent.add(rod, ...ends);
  const y = new THREE.Vector3(0, 1, 0);
  return {
    set(a, b) {
      const d = new THREE.Vector3().subVectors(b, a);
      const length = d.length();
      rod.visible = length > 1e-6;
      if (rod.visible) {
        rod.position.addVectors(a, b).multiplyScalar(0.5);
        rod.quaternion.setFromUnitVectors(y, d.divideScalar(length));
        rod.scale.set(1, length, 1);
      }
      ends[0].position.copy(a);
      ends[1].position.copy(b);
    },
  };
}
