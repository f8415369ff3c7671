//! `cut.html` in headless Chromium, on every bundled cone scenario: the map, the roundness
//! plots, the ball bar beside the cut at the tip height, the error budget's table and the
//! 3D view (three.js, WebGL) are drawn, the canvas non-empty.

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
fn every_bundled_cone_cut_page_renders_its_map_plots_budget_ball_bar_and_3d_view() {
    let Some(browser) = chromium_or_skip(
        "every_bundled_cone_cut_page_renders_its_map_plots_budget_ball_bar_and_3d_view",
    ) else {
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
        // The ball bar beside the cut at the tip height: one chart, both curves on one θ
        // axis, drawn (plotters' paths inside the inline SVG).
        let tip = dom
            .split("id=\"tip\"")
            .nth(1)
            .unwrap_or_else(|| panic!("{name}: no ball bar beside the cut"));
        let chart = &tip[..tip.find("</svg>").expect("the chart's SVG")];
        assert!(chart.contains("ball bar dL"), "{name}: the bar's curve");
        assert!(
            chart.contains("cut d at the tip height"),
            "{name}: the cut's"
        );
        assert!(chart.contains("θ (deg)"), "{name}: the θ axis");
        assert!(
            chart.matches("<path").count() + chart.matches("<polyline").count() >= 2,
            "{name}: the curves are drawn"
        );
        // The error budget: the program's row, at least one mechanism's and the interplay.
        let budget = dom
            .split("class=\"budget\"")
            .nth(1)
            .unwrap_or_else(|| panic!("{name}: no budget table"));
        let table = &budget[..budget.find("</table>").expect("the table's end")];
        assert!(
            table.contains("data-budget=\"programpath:–\""),
            "{name}: program row"
        );
        assert!(
            table.contains("data-budget=\"servo:–\""),
            "{name}: the common lag"
        );
        assert!(
            table.contains("data-budget=\"interaction:–\""),
            "{name}: interplay"
        );
        assert!(
            table.matches("<tr data-budget").count() >= 4,
            "{name}: the budget's rows"
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
