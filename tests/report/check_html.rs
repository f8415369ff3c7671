//! `check --html FILE` in headless Chromium: a program that turns the fork head's spindle
//! into the table and then plunges the cutter into it. The page names the colliding pair
//! with its depth (10 mm and 5 mm by hand: tests/check/views.rs works them out), draws the
//! scene in a non-empty 3D canvas with the pair in red, and opened on the second collision
//! (`#collision-2`, what the "next" button shows) re-poses the bodies for it.

use crate::common;
use crate::html::{chromium_or_skip, render};

/// The fork head into the table (machines/fork-head-ca.toml): A to 90° at Y 675, Z −340
/// lays the spindle housing 10 mm into the table (line 3); a plunge to Z −205 at A 0 puts
/// the cutter 5 mm into it (line 7).
const PROGRAM: &str = "G21 G90 G17\nG0 X0 Y675 Z-340 C0 A0\nG1 A90 F1800\nG1 A0\nG0 Z-100\nG0 Y0\n\
                       G1 Z-205 F600\nG0 Z0\nM2\n";

/// The number in `attr="…"` on the page's canvas.
fn canvas_number(dom: &str, attr: &str) -> usize {
    dom.split(&format!("{attr}=\""))
        .nth(1)
        .and_then(|rest| rest.split('"').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("the 3D view did not run (no {attr})"))
}

/// The text the page's script wrote into the label of the shown collision.
fn label(dom: &str) -> String {
    let rest = dom.split("id=\"scene-label\">").nth(1).expect("the label");
    rest[..rest.find('<').unwrap()].to_string()
}

#[test]
fn the_collision_page_shows_the_fork_head_in_the_table_in_3d() {
    let Some(browser) =
        chromium_or_skip("the_collision_page_shows_the_fork_head_in_the_table_in_3d")
    else {
        return;
    };
    let work = common::scratch("check-html", "fork-head");
    common::fork_head_scenario(&work, PROGRAM);
    let page = work.join("check.html");
    let run = common::mtsim(&[
        "-q",
        "check",
        &work.join("s.toml").display().to_string(),
        "--html",
        &page.display().to_string(),
    ]);
    assert_eq!(
        run.status.code(),
        Some(1),
        "violations: exit 1; {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (dom, png) = render(&browser, &page, &work);
    assert!(!png.is_empty());
    // The first collision shown: the deepest, named with its depth.
    let first = label(&dom);
    assert!(
        first.starts_with("1 of 2: table / spindle, depth 10.000 mm, line 3"),
        "{first}"
    );
    assert!(first.contains("A 90.000"), "{first}");
    let ink = canvas_number(&dom, "data-ink");
    let red = canvas_number(&dom, "data-red");
    eprintln!("first collision: {ink} pixels drawn, {red} of them the pair's red");
    assert!(ink > 10_000, "the 3D view drew {ink} pixels of 614,400");
    assert!(red > 1_000, "the colliding pair drew {red} red pixels");
    // The second, as the "next" button shows it: the bodies re-posed at the plunge.
    let second_page = work.join("check.html#collision-2");
    let (dom, _) = render(&browser, &second_page, &work);
    let second = label(&dom);
    assert!(
        second.starts_with("2 of 2: table / cutter, depth 5.000 mm, line 7"),
        "{second}"
    );
    assert!(
        second.contains("A 0.000") && second.contains("Z -205.000"),
        "{second}"
    );
    assert_eq!(canvas_number(&dom, "data-shown"), 1);
    assert!(canvas_number(&dom, "data-ink") > 10_000);
}
