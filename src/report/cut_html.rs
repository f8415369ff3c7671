//! `cut.html`: the cut cone on one self-contained page: the CMM's figures, the unrolled map
//! and the roundness plots (inline SVG), and a 3D view of the cone with its deviation
//! exaggerated (the factor stated) that the user turns with the mouse.
//!
//! The 3D view is three.js r159 (MIT, `src/report/vendor/three-LICENSE`), vendored from the
//! npm registry as its UMD build `build/three.min.js` (`npm pack three@0.159.0`; the last
//! release that ships one: later ones ship ES modules only) and inlined in a classic
//! `<script>`, so the page works offline and from `file://`. The mesh is the grid at 1° of θ:
//! each vertex at radius `ρ(z) + k d / cos α`, coloured by d on the maps' linear scale
//! (grey where not cut). After its first frame the page counts the canvas's non-background
//! pixels into `data-ink` on the canvas, which the browser test reads.

use super::cut_budget::{budget_section, CutBudget};
use super::escape::esc;
use crate::measure::cut::{CutFigures, CutSurface};

pub const CUT_HTML: &str = "cut.html";

/// three.js r159, UMD build, as published on the npm registry.
const THREE_JS: &str = include_str!("vendor/three-0.159.0.min.js");

/// The 3D mesh's θ step, deg.
const MESH_STEP_DEG: f64 = 1.0;

/// The exaggeration of d in the 3D view: the largest |d| is drawn as 4 % of the smallest
/// radius of the grid.
fn exaggeration(surface: &CutSurface, largest_um: f64) -> f64 {
    let smallest_mm = surface
        .envelope
        .rows
        .iter()
        .map(|r| r.radius_mm)
        .fold(f64::INFINITY, f64::min);
    (0.04 * smallest_mm / (largest_um.max(0.01) * 1e-3))
        .round()
        .max(1.0)
}

/// The mesh as JSON: heights, radii, θ (deg) and d (um, null where not cut) per vertex.
fn mesh_json(surface: &CutSurface) -> (String, f64) {
    let e = &surface.envelope;
    let per = ((MESH_STEP_DEG / e.step_deg).round() as usize).max(1);
    let columns: Vec<usize> = (0..e.column_count()).step_by(per).collect();
    let mut largest: f64 = 0.0;
    let mut d = Vec::new();
    for i in 0..e.rows.len() {
        for &j in &columns {
            let v = e.depth_um(j, i);
            if v.is_finite() {
                largest = largest.max(v.abs());
                d.push(format!("{v:.4}"));
            } else {
                d.push("null".to_string());
            }
        }
    }
    let list = |v: Vec<String>| v.join(",");
    let json = format!(
        "{{\"z\":[{}],\"r\":[{}],\"theta\":[{}],\"d\":[{}],\"cos_alpha\":{}}}",
        list(e.rows.iter().map(|r| format!("{:.4}", r.z_mm)).collect()),
        list(
            e.rows
                .iter()
                .map(|r| format!("{:.4}", r.radius_mm))
                .collect()
        ),
        list(
            columns
                .iter()
                .map(|&j| format!("{:.4}", j as f64 * e.step_deg))
                .collect()
        ),
        list(d),
        surface.geometry.cos_alpha()
    );
    (json, largest)
}

/// The page's pictures, as SVG text: the unrolled map, the roundness panels and the ball
/// bar beside the cut at the tip height (None without a bar reading).
pub struct Pictures<'a> {
    pub map: &'a str,
    pub polar: &'a str,
    pub tip: Option<&'a str>,
}

/// The ball bar beside the cut, with the sentence that says how to read it.
fn tip_section(tip: Option<&str>) -> String {
    match tip {
        Some(svg) => format!(
            "<h2 id=\"tip\">Ball bar and cut at the tip height</h2>\n<p>The same run read two ways: \
             the ball bar's radial deviation dL (not centred) and the cut's deviation d just above \
             the tip height, over the same θ. They agree where dL varies slowly against the cutter \
             (the bar's θ is the commanded tip's, the servos' lag ahead of where the cutter cuts); \
             d stays below dL where the cutter cannot follow a scallop or spike, and above the tip \
             the cut also shows what tilts the tool axis, which the bar cannot see (docs/cut.md).</p>\n{svg}\n"
        ),
        None => String::new(),
    }
}

/// What a CMM reports of the cut as HTML tables: the least-squares circle per height, the
/// cone angle error and the reversal marks (each with its axis's lost motion and the take-up
/// the levels were read outside of).
pub fn cmm_tables(figures: &CutFigures) -> String {
    let rows: String = figures
        .heights
        .iter()
        .map(|h| {
            format!(
                "<tr><td>{:.3}</td><td>{:.3}</td><td>{:+.3}, {:+.3}</td><td>{:+.3}</td></tr>",
                h.z_mm,
                h.roundness_um,
                h.centre_offset_um[0],
                h.centre_offset_um[1],
                h.diameter_error_um
            )
        })
        .collect();
    let marks: String = figures
        .marks
        .iter()
        .map(|m| {
            format!(
                "<tr><td>{}</td><td>{:.2}</td><td>{:+.3}</td><td>{}</td><td>{:.2} to {:.2}</td></tr>",
                esc(&m.axis),
                m.theta_deg,
                m.step_um,
                m.lost_motion_text(),
                m.take_up_deg[0],
                m.take_up_deg[1]
            )
        })
        .collect();
    let marks = if marks.is_empty() {
        "<p>No reversal marks: no axis's lost motion swings across its reversals.</p>\n".to_string()
    } else {
        format!(
            "<table><tr><th>axis</th><th>reversal θ (deg)</th><th>step (µm)</th>\
             <th>lost motion (µm, rotary arcsec)</th><th>take-up θ (deg)</th></tr>{marks}</table>\n"
        )
    };
    let angle = figures
        .cone_angle_error_urad
        .map_or("not measured".to_string(), |a| format!("{a:+.2} µrad"));
    format!(
        "<table><tr><th>z (mm)</th><th>roundness (µm)</th><th>centre x, y (µm)</th>\
         <th>diameter error (µm)</th></tr>{rows}</table>\n<p>Cone angle error: {angle}.</p>\n{marks}"
    )
}

/// The cut's section of a `simulate --cut` run's report page: the CMM's tables, the error
/// budget and a link to the cut's own page beside it.
pub fn run_section(figures: &CutFigures, budget: Option<&CutBudget>) -> String {
    format!(
        "<h2 id=\"cut\">The cut cone</h2>\n<p>The piece the run cuts, as a CMM measures it \
         (<a href=\"{CUT_HTML}\">{CUT_HTML}</a>: the map, the roundness plots and the 3D view). \
         Definitions: docs/cut.md.</p>\n{}{}",
        cmm_tables(figures),
        budget_section(budget)
    )
}

/// The page.
pub fn cut_html(
    title: &str,
    surface: &CutSurface,
    figures: &CutFigures,
    pictures: &Pictures<'_>,
    budget: Option<&CutBudget>,
) -> String {
    let (map_svg, polar_svg) = (pictures.map, pictures.polar);
    let tip = tip_section(pictures.tip);
    let budget = budget_section(budget);
    let (mesh, largest) = mesh_json(surface);
    let k = exaggeration(surface, largest);
    let cmm = cmm_tables(figures);
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>body{{font-family:sans-serif;margin:24px;color:#1e1e1e}}table{{border-collapse:collapse}}
td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}#view{{border:1px solid #ccc;cursor:grab}}</style>
</head><body>
<h1>{title}</h1>
<p>Cutter radius {r:.3} mm, flutes {fl:.1} mm; {how}. Definitions: docs/cut.md.</p>
<h2>What a CMM reports</h2>
{cmm}{budget}{tip}<h2>The surface, unrolled</h2>
{map_svg}
<h2>Roundness per height</h2>
{polar_svg}
<h2>3D view (drag to turn)</h2>
<p>Deviation exaggerated {k:.0}× (radius ρ + {k:.0} d / cos α); colour as the map, ±{largest:.2} µm.</p>
<canvas id="view" width="800" height="600"></canvas>
<script>{three}</script>
<script>
(function () {{
  var mesh = {mesh};
  var canvas = document.getElementById('view');
  var renderer;
  try {{ renderer = new THREE.WebGLRenderer({{canvas: canvas, antialias: true, preserveDrawingBuffer: true}}); }}
  catch (e) {{ canvas.setAttribute('data-ink', '0'); canvas.setAttribute('data-error', String(e)); return; }}
  renderer.setClearColor(0xffffff);
  var scene = new THREE.Scene();
  var camera = new THREE.PerspectiveCamera(35, canvas.width / canvas.height, 1, 5000);
  var nt = mesh.theta.length, nz = mesh.z.length, k = {k}, scale = {scale};
  var zMid = 0.5 * (mesh.z[0] + mesh.z[nz - 1]);
  var positions = [], colours = [], index = [];
  function colour(d) {{
    if (d === null) return [0.75, 0.75, 0.75];
    var v = Math.max(-1, Math.min(1, d / scale)), a = Math.abs(v);
    var c = v >= 0 ? [200, 30, 30] : [30, 80, 200];
    return c.map(function (x) {{ return (255 - (255 - x) * a) / 255; }});
  }}
  for (var i = 0; i < nz; i++) for (var j = 0; j < nt; j++) {{
    var d = mesh.d[i * nt + j], t = mesh.theta[j] * Math.PI / 180;
    var r = mesh.r[i] + (d === null ? 0 : k * d * 1e-3 / mesh.cos_alpha);
    positions.push(r * Math.cos(t), r * Math.sin(t), mesh.z[i] - zMid);
    colours.push.apply(colours, colour(d));
  }}
  for (var i = 0; i + 1 < nz; i++) for (var j = 0; j < nt; j++) {{
    var a = i * nt + j, b = i * nt + (j + 1) % nt, c = a + nt, e = b + nt;
    index.push(a, b, e, a, e, c);
  }}
  var geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
  geometry.setAttribute('color', new THREE.Float32BufferAttribute(colours, 3));
  geometry.setIndex(index);
  geometry.computeVertexNormals();
  var material = new THREE.MeshLambertMaterial({{vertexColors: true, side: THREE.DoubleSide}});
  var cone = new THREE.Mesh(geometry, material);
  var holder = new THREE.Group();
  holder.add(cone);
  holder.rotation.x = -1.1;
  scene.add(holder);
  scene.add(new THREE.AmbientLight(0xffffff, 1.2));
  var light = new THREE.DirectionalLight(0xffffff, 1.5);
  light.position.set(1, 2, 3);
  scene.add(light);
  geometry.computeBoundingSphere();
  camera.position.set(0, 0, 3.2 * geometry.boundingSphere.radius);
  camera.lookAt(0, 0, 0);
  function draw() {{ renderer.render(scene, camera); }}
  var dragging = null;
  canvas.addEventListener('pointerdown', function (ev) {{ dragging = [ev.clientX, ev.clientY]; }});
  window.addEventListener('pointerup', function () {{ dragging = null; }});
  canvas.addEventListener('pointermove', function (ev) {{
    if (!dragging) return;
    holder.rotation.z += (ev.clientX - dragging[0]) * 0.01;
    holder.rotation.x += (ev.clientY - dragging[1]) * 0.01;
    dragging = [ev.clientX, ev.clientY];
    draw();
  }});
  draw();
  // Count the pixels the first frame drew (for the browser test).
  var probe = document.createElement('canvas');
  probe.width = canvas.width; probe.height = canvas.height;
  var ctx = probe.getContext('2d');
  ctx.drawImage(canvas, 0, 0);
  var px = ctx.getImageData(0, 0, probe.width, probe.height).data, ink = 0;
  for (var p = 0; p < px.length; p += 4) if (px[p] < 245 || px[p + 1] < 245 || px[p + 2] < 245) ink++;
  canvas.setAttribute('data-ink', String(ink));
}})();
</script>
</body></html>
"#,
        title = esc(title),
        r = figures.cutter_radius_mm,
        fl = figures.flute_length_mm,
        how = if figures.commanded {
            "cut with the commanded motion (the program alone)"
        } else {
            "cut with the actual motion"
        },
        scale = largest.max(0.01),
        three = THREE_JS,
    )
}
