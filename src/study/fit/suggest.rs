//! What to measure next: candidate extra cone tests scored by the null space they leave.
//! Inputs: the present tests and parameters. Output: the best [`Suggestion`], if any.

use nalgebra::{DMatrix, Vector3};

use super::decomposition::Decomposition;
use super::measured::MeasuredTrace;
use super::model::{predict, record};
use super::params::{Param, MIN_VISIBILITY};
use super::result::Suggestion;
use crate::error::Result;
use crate::input::program::{ConeTest, Direction};
use crate::input::scenario::Scenario;
use crate::kinematics::LocationParam;
use crate::pipeline::Timing;
use crate::program::test_of;
use crate::program::tests::generated_cone_mut;
use crate::study::simulate::bar_geometry;

/// Scores candidate extra cone tests by the null space they leave (geometric part only).
pub(super) fn suggest(
    inputs: &[(Scenario, MeasuredTrace)],
    params: &[Param],
) -> Result<Option<Suggestion>> {
    let Some((base, cone)) = inputs
        .iter()
        .find_map(|(s, _)| test_of(s).generated_cone().map(|(c, _)| (s, *c)))
    else {
        return Ok(None);
    };
    let loc_params: Vec<LocationParam> = params
        .iter()
        .filter_map(|p| match p {
            Param::Location(l) => Some(*l),
            _ => None,
        })
        .collect();
    let sens = |scenario: &Scenario| -> Result<DMatrix<f64>> {
        let g = bar_geometry(scenario).expect("a cone");
        let samples = record(
            scenario,
            &scenario.machine,
            Direction::Ccw,
            Timing::Programmed,
        )?;
        let thetas: Vec<f64> = (0..360).map(|i| i as f64 + 0.5).collect();
        let mut j = DMatrix::zeros(thetas.len(), loc_params.len() + 1);
        let prior = scenario.machine.kinematics.location_errors;
        for (c, lp) in loc_params.iter().enumerate() {
            let p = predict(
                &g,
                &samples,
                Direction::Ccw,
                &prior.with(*lp, prior.get(*lp) + 1.0),
                &Vector3::zeros(),
                &thetas,
            )?;
            let m = predict(
                &g,
                &samples,
                Direction::Ccw,
                &prior.with(*lp, prior.get(*lp) - 1.0),
                &Vector3::zeros(),
                &thetas,
            )?;
            for i in 0..thetas.len() {
                j[(i, c)] = (p[i] - m[i]) / 2.0;
            }
        }
        j.column_mut(loc_params.len()).fill(1.0);
        Ok(j)
    };
    let with_cone = |c: ConeTest| -> Scenario {
        let mut s = base.clone();
        if let Some(cone) = generated_cone_mut(&mut s.program) {
            *cone = c;
        }
        s
    };
    // The present tests' geometric sensitivities (each with its own bar offset).
    let mut blocks = Vec::new();
    for (s, _) in inputs {
        if test_of(s).generated_cone().is_some() {
            blocks.push(sens(s)?);
        }
    }
    let z = cone.center_mm.z;
    let mut candidates = vec![
        ConeTest {
            center_mm: Vector3::new(
                cone.center_mm.x,
                cone.center_mm.y,
                if z > 150.0 { z - 100.0 } else { z + 100.0 },
            ),
            ..cone
        },
        ConeTest {
            center_mm: Vector3::new(cone.center_mm.x, cone.center_mm.y - 50.0, z),
            ..cone
        },
    ];
    if (cone.half_apex_deg - 15.0).abs() < 1e-9 && (cone.inclination_deg - 10.0).abs() < 1e-9 {
        candidates.push(ConeTest {
            half_apex_deg: 45.0,
            inclination_deg: 30.0,
            ..cone
        });
    } else {
        candidates.push(ConeTest {
            half_apex_deg: 15.0,
            inclination_deg: 10.0,
            ..cone
        });
    }
    let stack = |all: &[&DMatrix<f64>]| -> Decomposition {
        let rows: usize = all.iter().map(|b| b.nrows()).sum();
        let nl = loc_params.len();
        let mut j = DMatrix::zeros(rows, nl + all.len());
        let mut r0 = 0;
        for (k, b) in all.iter().enumerate() {
            j.view_mut((r0, 0), (b.nrows(), nl))
                .copy_from(&b.columns(0, nl));
            j.view_mut((r0, nl + k), (b.nrows(), 1)).fill(1.0);
            r0 += b.nrows();
        }
        // A column below MIN_VISIBILITY is not separated in any useful sense.
        let rows = (j.nrows().max(1) as f64).sqrt();
        let unseen: Vec<bool> = (0..j.ncols())
            .map(|c| j.column(c).norm() / rows < MIN_VISIBILITY)
            .collect();
        Decomposition::new(&j, &unseen)
    };
    // The location errors the present tests leave inseparable.
    let null_now = stack(&blocks.iter().collect::<Vec<_>>()).null_dim();
    if null_now == 0 {
        return Ok(None);
    }
    let mut best: Option<(usize, f64, ConeTest)> = None;
    for c in candidates {
        let extra = sens(&with_cone(c))?;
        let all: Vec<&DMatrix<f64>> = blocks.iter().chain(std::iter::once(&extra)).collect();
        let d = stack(&all);
        let smallest = d
            .relative
            .get(d.rank.saturating_sub(1))
            .copied()
            .unwrap_or(0.0);
        let better = match &best {
            None => true,
            Some((nd, sm, _)) => d.null_dim() < *nd || (d.null_dim() == *nd && smallest > *sm),
        };
        if better {
            best = Some((d.null_dim(), smallest, c));
        }
    }
    Ok(best.map(|(nd, _, c)| Suggestion {
        half_apex_deg: c.half_apex_deg,
        inclination_deg: c.inclination_deg,
        center_mm: c.center_mm.into(),
        ballbar_length_mm: c.ballbar_length_mm,
        null_dimensions_after: nd,
        text: format!(
            "add the cone {}/{} deg at O = ({}, {}, {}) mm, L = {} mm: it leaves {nd} inseparable combination(s) (now {null_now}); check that it fits the machine with `mtsim check`",
            c.half_apex_deg, c.inclination_deg, c.center_mm.x, c.center_mm.y, c.center_mm.z, c.ballbar_length_mm
        ),
    }))
}
