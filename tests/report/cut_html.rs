//! `cut.html` in headless Chromium, on every bundled cone scenario: the map, the roundness
//! plots and the 3D view (three.js, WebGL) are drawn, the canvas non-empty.

use crate::common;
use crate::html::{chromium_or_skip, render};

/// The bundled scenarios that cut a cone: the generated ones and the program file.
const CONES: &[&str] = &[
    "cone-15-10",
    "cone-15-10-offset",
    "cone-15-10-yt25",
    "cone-45-30",
    "file-cone-15-10-yt25",
];

#[test]
fn every_bundled_cone_cut_page_renders_its_map_plots_and_3d_view() {
    let Some(browser) =
        chromium_or_skip("every_bundled_cone_cut_page_renders_its_map_plots_and_3d_view")
    else {
        return;
    };
    for name in CONES {
        let work = common::scratch("cut-html", name);
        let out = work.join("cut");
        let scenario = format!("scenarios/{name}.toml");
        let run = common::mtsim(&["-q", "cut", &scenario, "-o", &out.display().to_string()]);
        assert!(
            run.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let (dom, png) = render(&browser, &out.join("cut.html"), &work);
        assert!(!png.is_empty());
        // The two SVGs are inline: the map's colour bar and one polar panel per height.
        assert!(dom.contains("d (µm)"), "{name}: the map");
        assert_eq!(
            dom.matches("Ø error").count(),
            3,
            "{name}: three polar panels"
        );
        // The 3D view drew: non-background pixels counted by the page after its first frame.
        let ink: usize = dom
            .split("data-ink=\"")
            .nth(1)
            .and_then(|rest| rest.split('"').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{name}: the 3D view did not run (no data-ink)"));
        assert!(
            ink > 10_000,
            "{name}: the 3D view drew {ink} pixels of 480,000"
        );
    }
}
