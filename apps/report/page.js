// The report page's script (nbv report, nbv reconstruct --html): a three.js view (orbit with
// the mouse), a run selector, a slider over the iterations, and a canvas of the curves.
// Iteration k shows the scans 1..k, the path through their views, and each candidate coloured by
// the gain it was given after scan k (visited views grey); the view chosen next carries a sphere.
// #status reads "rendered" once the first frame is drawn, or the error that stopped the page.
// It reads NBV_DATA, the run, scans and voxels the page carries (apps/report_html.cpp pageData).
(function () {
  'use strict';
  const status = document.getElementById('status');
  window.addEventListener('error', function (e) { status.textContent = 'error: ' + e.message; });
  const data = NBV_DATA;
  const viridis = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  function colormap(t) {
    t = Math.min(1, Math.max(0, t)) * 4;
    const k = Math.min(3, Math.floor(t)), f = t - k;
    return viridis[k].map(function (c, i) { return (c + f * (viridis[k + 1][i] - c)) / 255; });
  }
  const canvas = document.getElementById('view');
  const renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: true, preserveDrawingBuffer: true});
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf7f7f7);
  const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 50);
  camera.up.set(0, 0, 1);
  camera.position.set(1.3, -1.5, 1.2);
  const controls = new THREE.OrbitControls(camera, canvas);
  controls.target.set(0, 0, 0.2);
  controls.update();
  const grid = new THREE.GridHelper(1.2, 12, 0xbbbbbb, 0xdddddd);
  grid.rotation.x = Math.PI / 2;
  scene.add(grid);

  // Frusta of every view: 8 segments each, coloured per iteration.
  const [fx, fy] = data.frustum, depth = 0.07;
  const frustumPositions = [], apexes = [];
  data.views.forEach(function (v) {
    const p = new THREE.Vector3(v[0], v[1], v[2]);
    const axes = [new THREE.Vector3(v[3], v[6], v[9]), new THREE.Vector3(v[4], v[7], v[10]), new THREE.Vector3(v[5], v[8], v[11])];
    const corners = [[-1, -1], [1, -1], [1, 1], [-1, 1]].map(function (s) {
      return p.clone().addScaledVector(axes[0], s[0] * fx * depth).addScaledVector(axes[1], s[1] * fy * depth).addScaledVector(axes[2], depth);
    });
    for (let k = 0; k < 4; ++k) {
      frustumPositions.push(p, corners[k], corners[k], corners[(k + 1) % 4]);
    }
    apexes.push(p);
  });
  const frustumGeometry = new THREE.BufferGeometry().setFromPoints(frustumPositions);
  const frustumColors = new Float32Array(frustumPositions.length * 3).fill(0.55);
  frustumGeometry.setAttribute('color', new THREE.BufferAttribute(frustumColors, 3));
  scene.add(new THREE.LineSegments(frustumGeometry, new THREE.LineBasicMaterial({vertexColors: THREE.VertexColors})));

  // A map's voxels by class: a point cloud and a checkbox each (free space starts hidden).
  let voxelCount = 0;
  data.voxels.forEach(function (c) {
    if (c.centres.length === 0) return;
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(c.centres, 3));
    const color = new THREE.Color(c.color[0] / 255, c.color[1] / 255, c.color[2] / 255);
    const cloud = new THREE.Points(g, new THREE.PointsMaterial({size: data.voxel_size, color: color}));
    cloud.visible = c.name !== 'free';
    scene.add(cloud);
    voxelCount += c.centres.length / 3;
    const label = document.createElement('label');
    const box = document.createElement('input');
    box.type = 'checkbox';
    box.checked = cloud.visible;
    box.addEventListener('change', function () { cloud.visible = box.checked; render(); });
    label.style.color = '#' + color.getHexString();
    label.appendChild(box);
    label.appendChild(document.createTextNode(' ' + c.name + ' (' + c.meaning + '): ' + c.centres.length / 3 + ' \u00a0 '));
    document.getElementById('classes').appendChild(label);
  });

  const pathMaterial = new THREE.LineBasicMaterial({color: 0x111111});
  let path = null, points = null;
  const next = new THREE.Mesh(new THREE.SphereGeometry(0.018, 16, 12), new THREE.MeshBasicMaterial({color: 0x111111}));
  scene.add(next);

  const runSelect = document.getElementById('run');
  data.runs.forEach(function (run, i) {
    const option = document.createElement('option');
    option.value = i;
    option.textContent = run.label;
    runSelect.appendChild(option);
  });
  const slider = document.getElementById('iteration');
  const info = document.getElementById('info');

  function show() {
    const run = data.runs[+runSelect.value];
    const its = run.iterations;
    slider.max = its.length;
    const k = Math.min(+slider.value, its.length);
    // The scans 1..k, each in its own hue.
    const positions = [], colors = [];
    for (let i = 0; i < k; ++i) {
      const scan = data.scans[its[i].view] || [];
      const c = new THREE.Color().setHSL((0.55 + i * 0.137) % 1, 0.65, 0.45);
      for (let j = 0; j < scan.length; j += 3) {
        positions.push(scan[j], scan[j + 1], scan[j + 2]);
        colors.push(c.r, c.g, c.b);
      }
    }
    if (points) scene.remove(points);
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
    g.setAttribute('color', new THREE.Float32BufferAttribute(colors, 3));
    points = new THREE.Points(g, new THREE.PointsMaterial({size: 0.006, vertexColors: THREE.VertexColors}));
    scene.add(points);
    // The path through the views scanned so far.
    if (path) scene.remove(path);
    path = new THREE.Line(new THREE.BufferGeometry().setFromPoints(its.slice(0, k).map(function (it) { return apexes[it.view]; })), pathMaterial);
    scene.add(path);
    // Candidates by the gains after scan k; visited views grey.
    const gains = k >= 1 ? its[k - 1].gains : [];
    const finite = gains.filter(function (x) { return x !== null; });
    const lo = Math.min.apply(null, finite), hi = Math.max.apply(null, finite);
    const visited = new Set(its.slice(0, k).map(function (it) { return it.view; }));
    for (let v = 0; v < data.views.length; ++v) {
      const g = gains[v];
      const c = visited.has(v) || g === null || g === undefined ? [0.55, 0.55, 0.55] : colormap(hi > lo ? (g - lo) / (hi - lo) : 1);
      for (let j = 0; j < 16; ++j) frustumColors.set(c, (v * 16 + j) * 3);
    }
    frustumGeometry.attributes.color.needsUpdate = true;
    next.visible = k < its.length;
    if (next.visible) next.position.copy(apexes[its[k].view]);
    const now = its[k - 1];
    info.textContent = 'scan ' + k + ' of ' + its.length + ': view ' + now.view + ', coverage ' + now.coverage.toFixed(3) +
        ', entropy ' + (now.entropy_bits / run.max_entropy_bits).toFixed(4) + ' of the empty map' +
        (k < its.length ? '; next view ' + its[k].view : '');
    drawCurves(run, k);
    render();
  }

  function drawCurves(run, k) {
    const c = document.getElementById('curves'), ctx = c.getContext('2d');
    const w = c.width, h = c.height, m = 30;
    ctx.clearRect(0, 0, w, h);
    ctx.strokeStyle = '#999';
    ctx.strokeRect(m, 10, w - m - 10, h - m - 10);
    const n = run.iterations.length;
    const x = function (i) { return m + (w - m - 10) * i / n; };
    const y = function (v) { return 10 + (h - m - 10) * (1 - v); };
    function curve(values, color, label, row) {
      ctx.strokeStyle = color;
      ctx.beginPath();
      values.forEach(function (v, i) { if (i === 0) ctx.moveTo(x(i), y(v)); else ctx.lineTo(x(i), y(v)); });
      ctx.stroke();
      ctx.fillStyle = color;
      ctx.fillText(label, m + 8, 24 + 14 * row);
    }
    curve([0].concat(run.iterations.map(function (it) { return it.coverage; })), '#1f77b4', 'coverage', 0);
    // Entropy on its own scale, from its lowest value (bottom) to the empty map's (top).
    const entropy = [1].concat(run.iterations.map(function (it) { return it.entropy_bits / run.max_entropy_bits; }));
    const low = Math.min.apply(null, entropy);
    curve(entropy.map(function (e) { return low < 1 ? (e - low) / (1 - low) : 1; }), '#ff7f0e',
          'entropy, from ' + low.toFixed(4) + ' (bottom) to the empty map (top)', 1);
    ctx.strokeStyle = '#d62728';
    ctx.beginPath();
    ctx.moveTo(x(k), 10);
    ctx.lineTo(x(k), h - m);
    ctx.stroke();
    ctx.fillStyle = '#333';
    ctx.fillText('scans', w / 2, h - 8);
    ctx.fillText('0', m - 4, h - m + 12);
    ctx.fillText(String(n), w - 20, h - m + 12);
  }

  function resize() {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }
  function render() {
    renderer.render(scene, camera);
  }
  controls.addEventListener('change', render);
  window.addEventListener('resize', function () { resize(); render(); });
  slider.addEventListener('input', show);
  // Start at the last scan a decision followed, so that the candidates show their gains.
  function lastDecision() {
    const its = data.runs[+runSelect.value].iterations;
    slider.max = its.length;
    let k = its.length;
    while (k > 1 && its[k - 1].gains.length === 0) --k;
    return k;
  }
  resize();
  if (data.runs.length > 0) {
    runSelect.addEventListener('change', function () { slider.value = lastDecision(); show(); });
    slider.value = lastDecision();
    show();
  } else {  // a map alone: no iterations to walk
    document.getElementById('controls').style.display = 'none';
    document.getElementById('curves').style.display = 'none';
    next.visible = false;
    render();
  }
  status.textContent = 'rendered ' + data.views.length + ' views, ' + Object.keys(data.scans).length + ' scans and ' +
      voxelCount + ' voxels';
})();
