//! The page of `check --html FILE`: the limits and collisions summary, and a 3D view of the
//! machine's scene at the deepest collision: every body as the scene holds it (its shape and
//! its pose at that sample, [`crate::check::scene::snapshot`]), the tool tip's path, and the
//! colliding pair in red (the smaller body solid, the larger translucent), the others
//! translucent. Buttons step through the kept
//! collisions (deepest first), each re-posing the bodies; dragging turns the view about the
//! smaller body of the pair, the wheel zooms. `#collision-k` in the address opens the page
//! on the k-th.
//!
//! The 3D view is the vendored three.js r159 of the cut page ([`super::cut_html`]), inlined,
//! so the page works offline. The orbit is written here (the UMD build has no
//! OrbitControls): the camera sits at azimuth φ and elevation ε on a sphere of radius ρ
//! about the target, `eye = target + ρ (cos ε cos φ, cos ε sin φ, sin ε)`, Z up. After its
//! first frame the page counts the canvas's non-background pixels into `data-ink` (the
//! browser test reads it).

use std::fmt::Write;

use super::escape::esc;
use super::html::{check_section, CSS};
use crate::check::scene::snapshot::CollisionViews;
use crate::check::CheckReport;

/// three.js r159, UMD build, as published on the npm registry (see [`super::cut_html`]).
const THREE_JS: &str = include_str!("vendor/three-0.159.0.min.js");

/// The page for the check of scenario `name`.
pub fn render_check_page(name: &str, check: &CheckReport) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>mtsim check: {0}</title>\n<style>{CSS}#scene-view{{border:1px solid #ccc;cursor:grab;touch-action:none}}</style>\n</head>\n<body>\n\
         <h1>mtsim check: {0}</h1>\n<h2 id=\"check\">Limits and collisions</h2>\n{1}{2}\
         <p class=\"note\">Made by mtsim {3}.</p>\n</body>\n</html>\n",
        esc(name),
        check_section(check),
        scene_section(check.views.as_ref()),
        env!("CARGO_PKG_VERSION")
    )
}

/// The 3D view, or why there is none.
fn scene_section(views: Option<&CollisionViews>) -> String {
    let mut out = String::from("<h2 id=\"scene\">The collision in the machine</h2>\n");
    let Some(views) = views else {
        out.push_str("<p>No scene: collisions were not checked.</p>\n");
        return out;
    };
    if views.collisions.is_empty() {
        out.push_str("<p>No collision to show.</p>\n");
        return out;
    }
    let _ = writeln!(
        out,
        "<p>The machine's scene (machine frame, mm, Z up) at the deepest sample of each of the \
         {} deepest collisions, deepest first: the smaller body of the colliding pair solid \
         red, the larger translucent red, the other bodies translucent, the tool tip's path in \
         blue (every {} samples) with the tip marked. Drag to turn, wheel to zoom.</p>",
        views.collisions.len(),
        views.path_stride
    );
    out.push_str("<ol class=\"collisions\">\n");
    for c in &views.collisions {
        let _ = writeln!(
            out,
            "<li>{} / {}: depth {:.3} mm, line {}, t {:.3} s</li>",
            esc(&c.bodies[0]),
            esc(&c.bodies[1]),
            c.depth_mm,
            c.line,
            c.time_s
        );
    }
    out.push_str("</ol>\n");
    // `</` would end the script element early.
    let data = serde_json::to_string(views)
        .expect("plain data serializes")
        .replace("</", "<\\/");
    let _ = write!(
        out,
        "<p><button id=\"scene-prev\" type=\"button\">previous</button> \
         <button id=\"scene-next\" type=\"button\">next</button> \
         <span id=\"scene-label\"></span></p>\n\
         <canvas id=\"scene-view\" width=\"960\" height=\"640\"></canvas>\n\
         <script>{THREE_JS}</script>\n<script>\nvar MTSIM_VIEWS = {data};\n{VIEWER}</script>\n"
    );
    out
}

/// The viewer: builds the bodies of one collision, the path, the orbit and the stepping.
const VIEWER: &str = r#"(function () {
  var data = MTSIM_VIEWS;
  var canvas = document.getElementById('scene-view');
  var label = document.getElementById('scene-label');
  var renderer;
  try { renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: true, preserveDrawingBuffer: true}); }
  catch (e) { canvas.setAttribute('data-ink', '0'); canvas.setAttribute('data-error', String(e)); return; }
  renderer.setClearColor(0xffffff);
  var scene = new THREE.Scene();
  var camera = new THREE.PerspectiveCamera(35, canvas.width / canvas.height, 1, 1e6);
  camera.up.set(0, 0, 1);
  scene.add(new THREE.AmbientLight(0xffffff, 1.1));
  var light = new THREE.DirectionalLight(0xffffff, 1.6);
  light.position.set(1, -2, 3);
  scene.add(light);
  if (data.tip_path_mm.length > 1) {
    var flat = [];
    data.tip_path_mm.forEach(function (p) { flat.push(p[0], p[1], p[2]); });
    var pathGeometry = new THREE.BufferGeometry();
    pathGeometry.setAttribute('position', new THREE.Float32BufferAttribute(flat, 3));
    scene.add(new THREE.Line(pathGeometry, new THREE.LineBasicMaterial({color: 0x1f6fd0})));
  }
  var tipMark = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({color: 0x1f6fd0}));
  scene.add(tipMark);
  var bodies = new THREE.Group();
  scene.add(bodies);
  var colours = {table: 0x8c8c8c, cradle: 0x9c8a6a, tool: 0xc08a2a, bar: 0x5a9a5a, head: 0x6a8caf};

  // The convex hull of two circles (centre, unit normal, radius): two rings of n points
  // joined side to side, each closed by a fan.
  function hullGeometry(circles) {
    var n = 64, pos = [], idx = [];
    circles.forEach(function (c) {
      var nrm = new THREE.Vector3().fromArray(c[1]).normalize();
      var u = Math.abs(nrm.x) < 0.9 ? new THREE.Vector3(1, 0, 0) : new THREE.Vector3(0, 1, 0);
      u.sub(nrm.clone().multiplyScalar(u.dot(nrm))).normalize();
      var v = new THREE.Vector3().crossVectors(nrm, u);
      for (var k = 0; k < n; k++) {
        var t = 2 * Math.PI * k / n;
        var p = new THREE.Vector3().fromArray(c[0])
          .addScaledVector(u, c[2] * Math.cos(t)).addScaledVector(v, c[2] * Math.sin(t));
        pos.push(p.x, p.y, p.z);
      }
    });
    pos.push.apply(pos, circles[0][0]);
    pos.push.apply(pos, circles[1][0]);
    for (var k = 0; k < n; k++) {
      var a = k, b = (k + 1) % n;
      idx.push(a, b, n + b, a, n + b, n + a);
      idx.push(2 * n, b, a, 2 * n + 1, n + a, n + b);
    }
    var g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
    g.setIndex(idx);
    g.computeVertexNormals();
    return g;
  }
  function geometryOf(s) {
    if (s.kind === 'cuboid') return new THREE.BoxGeometry(2 * s.half_mm[0], 2 * s.half_mm[1], 2 * s.half_mm[2]);
    if (s.kind === 'cylinder') return new THREE.CylinderGeometry(s.radius_mm, s.radius_mm, 2 * s.half_height_mm, 48);
    if (s.kind === 'ball') return new THREE.SphereGeometry(s.radius_mm, 32, 16);
    return hullGeometry(s.circles);
  }

  var target = new THREE.Vector3(), azimuth = -1.0, elevation = 0.45, distance = 1000;
  function place() {
    var ce = Math.cos(elevation);
    camera.position.set(
      target.x + distance * ce * Math.cos(azimuth),
      target.y + distance * ce * Math.sin(azimuth),
      target.z + distance * Math.sin(elevation));
    camera.lookAt(target);
  }
  function draw() { place(); renderer.render(scene, camera); }

  var shown = 0;
  function show(k) {
    shown = (k + data.collisions.length) % data.collisions.length;
    var c = data.collisions[shown];
    bodies.children.slice().forEach(function (m) { bodies.remove(m); m.geometry.dispose(); m.material.dispose(); });
    var pair = [], all = new THREE.Box3();
    c.bodies_placed.forEach(function (b) {
      var hit = b.name === c.bodies[0] || b.name === c.bodies[1];
      var material = new THREE.MeshLambertMaterial({color: colours[b.carrier] || 0x999999, transparent: true,
        opacity: 0.3, depthWrite: false, side: THREE.DoubleSide});
      var mesh = new THREE.Mesh(geometryOf(b.shape), material);
      mesh.position.fromArray(b.position_mm);
      mesh.quaternion.set(b.rotation_xyzw[0], b.rotation_xyzw[1], b.rotation_xyzw[2], b.rotation_xyzw[3]);
      mesh.renderOrder = 1;
      bodies.add(mesh);
      mesh.updateMatrixWorld(true);
      var box = new THREE.Box3().setFromObject(mesh);
      all.union(box);
      if (hit) pair.push({mesh: mesh, box: box, size: box.getSize(new THREE.Vector3()).length()});
    });
    // The pair: the smaller body solid red, the larger one translucent red, so that the
    // part of the smaller inside it shows. The view turns about the smaller.
    pair.sort(function (a, b) { return a.size - b.size; });
    pair.forEach(function (p, k) {
      p.mesh.material.dispose();
      p.mesh.material = k === 0
        ? new THREE.MeshLambertMaterial({color: 0xd01c1c, emissive: 0x400000, side: THREE.DoubleSide})
        : new THREE.MeshLambertMaterial({color: 0xe04040, transparent: true, opacity: 0.55, depthWrite: false, side: THREE.DoubleSide});
      p.mesh.renderOrder = k === 0 ? 0 : 2;
    });
    tipMark.position.fromArray(c.tip_mm);
    (pair.length ? pair[0].box : all).getCenter(target);
    var size = all.getSize(new THREE.Vector3()).length();
    distance = Math.max(1.3 * size, 50);
    tipMark.scale.setScalar(Math.max(size / 300, 0.5));
    var axes = c.axes.map(function (a) { return a[0] + ' ' + a[1].toFixed(3); }).join(', ');
    label.textContent = (shown + 1) + ' of ' + data.collisions.length + ': ' + c.bodies[0] + ' / ' + c.bodies[1] +
      ', depth ' + c.depth_mm.toFixed(3) + ' mm, line ' + c.line + ', t ' + c.time_s.toFixed(3) + ' s (' + axes + ')';
    canvas.setAttribute('data-shown', String(shown));
    draw();
  }
  document.getElementById('scene-prev').addEventListener('click', function () { show(shown - 1); });
  document.getElementById('scene-next').addEventListener('click', function () { show(shown + 1); });
  var dragging = null;
  canvas.addEventListener('pointerdown', function (ev) { dragging = [ev.clientX, ev.clientY]; });
  window.addEventListener('pointerup', function () { dragging = null; });
  canvas.addEventListener('pointermove', function (ev) {
    if (!dragging) return;
    azimuth -= (ev.clientX - dragging[0]) * 0.01;
    elevation = Math.max(-1.5, Math.min(1.5, elevation + (ev.clientY - dragging[1]) * 0.01));
    dragging = [ev.clientX, ev.clientY];
    draw();
  });
  canvas.addEventListener('wheel', function (ev) {
    ev.preventDefault();
    distance *= Math.exp(0.001 * ev.deltaY);
    draw();
  }, {passive: false});
  // `#collision-k` opens the page on the k-th collision (1-based).
  var asked = /^#collision-(\d+)$/.exec(window.location.hash);
  show(asked ? parseInt(asked[1], 10) - 1 : 0);
  // Count the pixels the first frame drew (for the browser test).
  var probe = document.createElement('canvas');
  probe.width = canvas.width; probe.height = canvas.height;
  var ctx = probe.getContext('2d');
  ctx.drawImage(canvas, 0, 0);
  var px = ctx.getImageData(0, 0, probe.width, probe.height).data, ink = 0, red = 0;
  for (var p = 0; p < px.length; p += 4) {
    if (px[p] < 245 || px[p + 1] < 245 || px[p + 2] < 245) ink++;
    if (px[p] > 150 && px[p + 1] < 90 && px[p + 2] < 90) red++;
  }
  canvas.setAttribute('data-ink', String(ink));
  canvas.setAttribute('data-red', String(red));
})();
"#;
