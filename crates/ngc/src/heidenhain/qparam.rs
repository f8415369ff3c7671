//! Q parameters: the global `Q0`-`Q1999`, the program-local `QL0`-`QL499` and the
//! remanent `QR0`-`QR499`, and the formulas that set them.
//!
//! HEIDENHAIN TNC 640 Klartext programming manual, "Programming Q parameters": basic
//! arithmetic `FN 0`-`FN 5`, trigonometry `FN 6`-`FN 8`, `FN 13`, and formulas
//! `Q1 = 5 * SIN(30) + SQRT(Q2)` with the operators `+ - * / ^` and brackets; angles in
//! degrees.

use std::ops::Range;

use crate::expr::MAX_NESTING;
use crate::lex::{LineError, LineResult};

/// The parameter kinds and their sizes.
const KINDS: [(&str, usize); 3] = [("QL", 500), ("QR", 500), ("Q", 2000)];

/// All Q parameters, zero at the start.
pub(super) struct Qparams {
    values: [Vec<f64>; 3],
}

impl Qparams {
    pub(super) fn new() -> Qparams {
        Qparams {
            values: KINDS.map(|(_, n)| vec![0.0; n]),
        }
    }

    /// The slot of a reference `Q12`, `QL3`, `QR4` (all of `name`), at `span`.
    fn slot(name: &str, span: Range<usize>) -> LineResult<(usize, usize)> {
        let upper = name.to_ascii_uppercase();
        for (kind, (prefix, size)) in KINDS.iter().enumerate() {
            if let Some(number) = upper.strip_prefix(prefix) {
                if let Some(n) = number
                    .parse::<usize>()
                    .ok()
                    .filter(|n| n < size && number.bytes().all(|b| b.is_ascii_digit()))
                {
                    return Ok((kind, n));
                }
                if !number.is_empty() && number.bytes().all(|b| b.is_ascii_digit()) {
                    return Err(LineError::new(
                        span,
                        format!("`{name}`: expected {prefix}0 to {prefix}{}", size - 1),
                        "parameter out of range",
                    ));
                }
            }
        }
        let why = if upper.starts_with("QS") {
            " (QS string parameters are not supported)"
        } else {
            ""
        };
        Err(LineError::new(
            span,
            format!("`{name}`: expected a Q parameter such as Q1, QL2 or QR3{why}"),
            "expected a Q parameter",
        ))
    }

    /// The value of the reference `name` (`Q12`, `QL3`, `QR4`).
    pub(super) fn get_ref(&self, name: &str, span: Range<usize>) -> LineResult<f64> {
        let (k, n) = Self::slot(name, span.clone())?;
        let v = self.values[k][n];
        if v.is_nan() {
            // Only `unknown` stores NaN (`set_ref` refuses it).
            return Err(LineError::new(
                span,
                format!("`{name}` has no value here: the `PLANE … STAY` before it stores the rotary axes' angles in Q120-Q122 from the machine's kinematics, which mtsim's Klartext reader computes for table-table AC and BC machines only (KP \"Automatic positioning: MOVE/TURN/STAY\")"),
                "rotary angle not computed",
            )
            .help("use PLANE … TURN, or move the rotary axes by angles of your own"));
        }
        Ok(v)
    }

    /// Marks the global parameter `Qn` as having no known value: reading it is refused.
    pub(super) fn unknown(&mut self, n: usize) {
        self.values[2][n] = f64::NAN;
    }

    /// Sets the parameter `name` to `v`.
    pub(super) fn set_ref(&mut self, name: &str, v: f64, span: Range<usize>) -> LineResult<()> {
        let (k, n) = Self::slot(name, span.clone())?;
        if !v.is_finite() {
            return Err(LineError::new(
                span,
                format!("`{name}` set to {v}: expected a finite value (a division by zero?)"),
                "not a number",
            ));
        }
        self.values[k][n] = v;
        Ok(())
    }

    /// Global parameter `Qn` (cycle parameters).
    pub(super) fn q(&self, n: usize) -> f64 {
        self.values[2][n]
    }

    /// Evaluates the formula `text`, which starts at byte `at` of the block.
    pub(super) fn formula(&self, text: &str, at: usize) -> LineResult<f64> {
        let mut p = Parser {
            b: text.as_bytes(),
            text,
            k: 0,
            at,
            q: self,
            depth: 0,
        };
        let v = p.sum()?;
        p.blanks();
        if p.k < p.b.len() {
            return Err(p.error("expected an operator + - * / ^ or the end of the formula"));
        }
        if !v.is_finite() {
            return Err(LineError::new(
                at..at + text.len(),
                format!("the Q-parameter formula `{}` has no finite value: expected a formula without a division by zero or the root of a negative number (a value read with FN 18 from a position set by hand is the program's start position here)", text.trim()),
                "not a number",
            ));
        }
        Ok(v)
    }
}

struct Parser<'a> {
    b: &'a [u8],
    text: &'a str,
    k: usize,
    at: usize,
    q: &'a Qparams,
    depth: usize,
}

impl Parser<'_> {
    fn error(&self, what: &str) -> LineError {
        let k = self.k.min(self.b.len());
        LineError::new(
            self.at + k..self.at + self.b.len(),
            format!("formula: {what}"),
            "bad formula",
        )
    }

    fn blanks(&mut self) {
        while self.k < self.b.len() && self.b[self.k].is_ascii_whitespace() {
            self.k += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.blanks();
        self.b.get(self.k).copied()
    }

    fn sum(&mut self) -> LineResult<f64> {
        let mut v = self.product()?;
        while let Some(op @ (b'+' | b'-')) = self.peek() {
            self.k += 1;
            let r = self.product()?;
            v = if op == b'+' { v + r } else { v - r };
        }
        Ok(v)
    }

    fn product(&mut self) -> LineResult<f64> {
        let mut v = self.power()?;
        while let Some(op @ (b'*' | b'/')) = self.peek() {
            self.k += 1;
            let r = self.power()?;
            v = if op == b'*' { v * r } else { v / r };
        }
        Ok(v)
    }

    fn power(&mut self) -> LineResult<f64> {
        let v = self.unary()?;
        if self.peek() == Some(b'^') {
            self.k += 1;
            return Ok(v.powf(self.power()?));
        }
        Ok(v)
    }

    fn unary(&mut self) -> LineResult<f64> {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            return Err(self.error(&format!("more than {MAX_NESTING} nested levels")));
        }
        let v = match self.peek() {
            Some(b'+') => {
                self.k += 1;
                self.unary()
            }
            Some(b'-') => {
                self.k += 1;
                self.unary().map(|v| -v)
            }
            _ => self.primary(),
        };
        self.depth -= 1;
        v
    }

    fn primary(&mut self) -> LineResult<f64> {
        match self.peek() {
            Some(b'(') => {
                self.k += 1;
                let v = self.sum()?;
                if self.peek() != Some(b')') {
                    return Err(self.error("expected `)`"));
                }
                self.k += 1;
                Ok(v)
            }
            Some(c) if c.is_ascii_digit() || c == b'.' => {
                let start = self.k;
                while self.k < self.b.len()
                    && (self.b[self.k].is_ascii_digit() || self.b[self.k] == b'.')
                {
                    self.k += 1;
                }
                self.text[start..self.k]
                    .parse()
                    .map_err(|_| self.error("expected a number"))
            }
            Some(c) if c.is_ascii_alphabetic() => {
                let start = self.k;
                while self.k < self.b.len() && self.b[self.k].is_ascii_alphanumeric() {
                    self.k += 1;
                }
                let name = &self.text[start..self.k];
                let upper = name.to_ascii_uppercase();
                if upper.starts_with('Q')
                    && upper[1..]
                        .trim_start_matches(['L', 'R'])
                        .bytes()
                        .all(|b| b.is_ascii_digit())
                {
                    return self.q.get_ref(name, self.at + start..self.at + self.k);
                }
                if upper == "PI" {
                    return Ok(std::f64::consts::PI);
                }
                let f = function(&upper).ok_or_else(|| {
                    self.k = start;
                    self.error(&format!("`{name}`: expected a number, a Q parameter, `(` or a function SIN COS TAN ASIN ACOS ATAN SQRT SQ ABS INT FRAC LN LOG EXP NEG SGN"))
                })?;
                Ok(f(self.unary()?))
            }
            _ => Err(self.error("expected a number, a Q parameter, `(` or a function")),
        }
    }
}

/// The formula functions, angles in degrees.
fn function(name: &str) -> Option<fn(f64) -> f64> {
    Some(match name {
        "SIN" => |x: f64| x.to_radians().sin(),
        "COS" => |x: f64| x.to_radians().cos(),
        "TAN" => |x: f64| x.to_radians().tan(),
        "ASIN" => |x: f64| x.asin().to_degrees(),
        "ACOS" => |x: f64| x.acos().to_degrees(),
        "ATAN" => |x: f64| x.atan().to_degrees(),
        "SQRT" => f64::sqrt,
        "SQ" => |x: f64| x * x,
        "ABS" => f64::abs,
        "INT" => f64::trunc,
        "FRAC" => f64::fract,
        "LN" => f64::ln,
        "LOG" => f64::log10,
        "EXP" => f64::exp,
        "NEG" => |x: f64| -x,
        "SGN" => |x: f64| {
            if x > 0.0 {
                1.0
            } else if x < 0.0 {
                -1.0
            } else {
                0.0
            }
        },
        _ => return None,
    })
}
