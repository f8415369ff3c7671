//! The study file (TOML): a base scenario, the keys it varies and how (docs/studies.md).
//!
//! A grid varies one or two keys over listed values or `from`/`to`/`step`; a random study
//! draws `samples` points, each key from its own distribution (uniform, normal, optionally
//! truncated), with a `seed`. The points are made here, in order, before any runs.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::random::{normal_cdf, Rng};
use crate::error::{Error, Result};
use crate::input::overrides::KeyPath;
use crate::input::scenario::resolve;
use crate::input::toml_text::{self, value_error};

/// Most points a study may hold: beyond it the study is refused before it starts.
pub const MAX_POINTS: usize = 10_000_000;

/// The study file as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// The base scenario, relative to the study file.
    pub scenario: String,
    /// Points of a random study.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples: Option<usize>,
    /// Seed of a random study's generator.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// The G limit of the share plot, um.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub g_limit_um: Option<f64>,
    pub vary: Vec<VaryEntry>,
}

/// One `[[vary]]` table: a key and exactly one way of giving its values.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VaryEntry {
    pub key: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub values: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub from: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub to: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
    /// `[lo, hi]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uniform: Option<[f64; 2]>,
    /// `[mean, sd]`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 2]>,
    /// Truncation of a normal distribution.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
}

/// How one key's values are given.
#[derive(Clone, Debug, PartialEq)]
pub enum Sampling {
    /// Grid values, in order.
    Grid(Vec<f64>),
    Uniform {
        lo: f64,
        hi: f64,
    },
    /// Normal, redrawn until inside [min, max].
    Normal {
        mean: f64,
        sd: f64,
        min: f64,
        max: f64,
    },
}

/// A varied key.
#[derive(Clone, Debug, PartialEq)]
pub struct Factor {
    pub key: KeyPath,
    pub sampling: Sampling,
}

/// A study, checked: its base scenario, keys and points.
#[derive(Clone, Debug)]
pub struct StudySpec {
    pub file: StudyFile,
    pub scenario: PathBuf,
    pub factors: Vec<Factor>,
    /// Random (true) or grid.
    pub random: bool,
}

impl StudySpec {
    /// Reads and checks the study file at `path`: every error names the file, the line and
    /// what was expected.
    pub fn load(path: &Path) -> Result<StudySpec> {
        let text = toml_text::read_text(path)?;
        let file: StudyFile = toml_text::parse(path, &text)?;
        toml_text::check_numbers(path, &text)?;
        let err = |key: &str, message: String| value_error(path, &text, "vary", key, message);
        if file.vary.is_empty() {
            return Err(Error::invalid(
                path,
                "a study needs at least one [[vary]] table with a `key`",
            ));
        }
        let mut factors = Vec::new();
        for v in &file.vary {
            let key: KeyPath = v.key.parse().map_err(|m| err("key", m))?;
            factors.push(Factor {
                key,
                sampling: sampling(v).map_err(|(k, m)| err(k, format!("`{}`: {m}", v.key)))?,
            });
        }
        let random = factors
            .iter()
            .any(|f| !matches!(f.sampling, Sampling::Grid(_)));
        if random
            && factors
                .iter()
                .any(|f| matches!(f.sampling, Sampling::Grid(_)))
        {
            return Err(err(
                "key",
                "a study is a grid (values, from/to/step) or random (uniform, normal), not both"
                    .into(),
            ));
        }
        let top = |key: &str, m: &str| value_error(path, &text, "", key, m.to_string());
        if random {
            match file.samples {
                Some(n) if (1..=MAX_POINTS).contains(&n) => {}
                Some(_) => {
                    return Err(top(
                        "samples",
                        &format!("expected 1 to {MAX_POINTS} points"),
                    ))
                }
                None => {
                    return Err(Error::invalid(
                        path,
                        "a random study needs `samples` (points) and `seed`",
                    ))
                }
            }
            if file.seed.is_none() {
                return Err(Error::invalid(path, "a random study needs `seed` (a whole number): the same seed gives the same points"));
            }
        } else {
            if factors.len() > 2 {
                return Err(err(
                    "key",
                    "a grid varies one or two keys; vary more with a random study".into(),
                ));
            }
            if file.samples.is_some() || file.seed.is_some() {
                return Err(top(
                    "samples",
                    "`samples` and `seed` belong to a random study (uniform, normal)",
                ));
            }
        }
        if let Some(g) = file.g_limit_um {
            if g <= 0.0 {
                return Err(top("g_limit_um", "expected a G limit > 0 um"));
            }
        }
        let spec = StudySpec {
            scenario: resolve(path, &file.scenario),
            file,
            factors,
            random,
        };
        if spec.len() > MAX_POINTS {
            return Err(Error::invalid(
                path,
                format!(
                    "the grid holds {} points, more than {MAX_POINTS}",
                    spec.len()
                ),
            ));
        }
        Ok(spec)
    }

    /// Points in the study.
    pub fn len(&self) -> usize {
        if self.random {
            return self.file.samples.unwrap_or(0);
        }
        self.factors
            .iter()
            .map(|f| match &f.sampling {
                Sampling::Grid(v) => v.len(),
                _ => 1,
            })
            .product()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The varied keys, in the order of the file.
    pub fn keys(&self) -> Vec<KeyPath> {
        self.factors.iter().map(|f| f.key.clone()).collect()
    }

    /// Every point's values, one per key. A grid of two keys runs the second key fastest; a
    /// random study draws point by point, key by key, from one generator.
    pub fn points(&self) -> Vec<Vec<f64>> {
        if !self.random {
            let grids: Vec<&[f64]> = self
                .factors
                .iter()
                .map(|f| match &f.sampling {
                    Sampling::Grid(v) => v.as_slice(),
                    _ => &[],
                })
                .collect();
            return match grids[..] {
                [a] => a.iter().map(|&x| vec![x]).collect(),
                [a, b] => a
                    .iter()
                    .flat_map(|&x| b.iter().map(move |&y| vec![x, y]))
                    .collect(),
                _ => Vec::new(),
            };
        }
        let mut rng = Rng::new(self.file.seed.unwrap_or(0));
        (0..self.len())
            .map(|_| {
                self.factors
                    .iter()
                    .map(|f| draw(&f.sampling, &mut rng))
                    .collect()
            })
            .collect()
    }
}

fn draw(s: &Sampling, rng: &mut Rng) -> f64 {
    match *s {
        Sampling::Grid(ref v) => v[0],
        Sampling::Uniform { lo, hi } => lo + (hi - lo) * rng.unit(),
        Sampling::Normal { mean, sd, min, max } => loop {
            // The window holds at least 10⁻³ of the mass (checked on loading): on average at
            // most 1,000 draws.
            let x = mean + sd * rng.standard_normal();
            if (min..=max).contains(&x) {
                break x;
            }
        },
    }
}

/// The sampling of one `[[vary]]` table, or the offending key and why.
pub fn sampling(v: &VaryEntry) -> std::result::Result<Sampling, (&'static str, String)> {
    let given = [
        v.values.is_some(),
        v.from.is_some() || v.to.is_some() || v.step.is_some(),
        v.uniform.is_some(),
        v.normal.is_some(),
    ];
    if given.iter().filter(|g| **g).count() != 1 {
        return Err((
            "key",
            "give exactly one of `values`, `from`/`to`/`step`, `uniform` or `normal`".into(),
        ));
    }
    if (v.min.is_some() || v.max.is_some()) && v.normal.is_none() {
        return Err((
            "min",
            "`min` and `max` truncate a `normal` distribution".into(),
        ));
    }
    if let Some(values) = &v.values {
        if values.is_empty() {
            return Err(("values", "expected at least one value".into()));
        }
        return Ok(Sampling::Grid(values.clone()));
    }
    if let Some([lo, hi]) = v.uniform {
        if lo >= hi {
            return Err((
                "uniform",
                format!("expected [lo, hi] with lo < hi, got [{lo}, {hi}]"),
            ));
        }
        return Ok(Sampling::Uniform { lo, hi });
    }
    if let Some([mean, sd]) = v.normal {
        let (min, max) = (
            v.min.unwrap_or(f64::NEG_INFINITY),
            v.max.unwrap_or(f64::INFINITY),
        );
        if sd <= 0.0 {
            return Err((
                "normal",
                format!("expected [mean, sd] with sd > 0, got sd = {sd}"),
            ));
        }
        let mass = normal_cdf((max - mean) / sd) - normal_cdf((min - mean) / sd);
        if !(mass >= 1e-3) {
            return Err(("min", format!("the window [{min}, {max}] holds {mass:.2e} of the normal distribution; expected at least 1e-3")));
        }
        return Ok(Sampling::Normal { mean, sd, min, max });
    }
    let (Some(from), Some(to), Some(step)) = (v.from, v.to, v.step) else {
        return Err(("from", "a grid range needs `from`, `to` and `step`".into()));
    };
    if !(step > 0.0) || to < from {
        return Err((
            "step",
            format!("expected from <= to and step > 0, got from {from}, to {to}, step {step}"),
        ));
    }
    let n = ((to - from) / step + 1e-9).floor();
    if n >= MAX_POINTS as f64 {
        return Err((
            "step",
            format!("the range holds more than {MAX_POINTS} values"),
        ));
    }
    Ok(Sampling::Grid(
        (0..=n as usize).map(|i| from + i as f64 * step).collect(),
    ))
}
