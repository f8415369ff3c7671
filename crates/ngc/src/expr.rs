//! Parameters and `[ ]` expressions.
//!
//! Numbered parameters `#1`..`#9999`, named local `#<name>` (scoped to a subroutine call)
//! and global `#<_name>`. Expressions follow LinuxCNC: binary operators, lowest precedence
//! first, all left-associative:
//!
//! ```text
//! AND OR XOR  <  EQ NE GT GE LT LE  <  + -  <  * / MOD  <  **
//! ```
//!
//! and the functions `ABS ACOS ASIN ATAN[y]/[x] COS EXP FIX FUP ROUND LN SIN SQRT TAN
//! EXISTS[#<name>]`, angles in degrees. Comparisons and logic give 1 or 0.
//!
//! The evaluator recurses once per nesting level (a `[`, a function's `[`, a leading sign,
//! a `#` that takes a value), so a line deepens the stack only up to [`MAX_NESTING`]
//! levels; deeper nesting is an error at the first level beyond it.

use std::collections::HashMap;
use std::ops::Range;

/// Highest parameter number.
pub const MAX_PARAMETER: usize = 9999;

/// A parameter a line names.
#[derive(Clone, Debug, PartialEq)]
pub enum Param {
    Numbered(usize),
    /// Lower-case name without blanks; global when it starts with `_`.
    Named(String),
}

/// The parameter store.
#[derive(Clone, Debug)]
pub struct Params {
    pub numbered: Vec<f64>,
    pub globals: HashMap<String, f64>,
    /// One map per subroutine call level; the last is the current one.
    pub locals: Vec<HashMap<String, f64>>,
    /// The meaning of a numbered system parameter the dialect has and mtsim does not give
    /// (Fanuc `#3011`, the date): reading it is an error naming that, never a 0.
    pub unmodelled: Option<fn(usize) -> Option<&'static str>>,
}

impl Params {
    pub fn new() -> Params {
        Params {
            numbered: vec![0.0; MAX_PARAMETER + 1],
            globals: HashMap::new(),
            locals: vec![HashMap::new()],
            unmodelled: None,
        }
    }

    pub fn get(&self, p: &Param) -> Option<f64> {
        match p {
            Param::Numbered(n) => self.numbered.get(*n).copied(),
            Param::Named(name) if name.starts_with('_') => self.globals.get(name).copied(),
            Param::Named(name) => self.locals.last().and_then(|m| m.get(name)).copied(),
        }
    }

    pub fn set(&mut self, p: &Param, value: f64) {
        match p {
            Param::Numbered(n) => {
                if let Some(slot) = self.numbered.get_mut(*n) {
                    *slot = value;
                }
            }
            Param::Named(name) if name.starts_with('_') => {
                self.globals.insert(name.clone(), value);
            }
            Param::Named(name) => {
                if let Some(m) = self.locals.last_mut() {
                    m.insert(name.clone(), value);
                }
            }
        }
    }
}

impl Default for Params {
    fn default() -> Self {
        Params::new()
    }
}

/// Deepest nesting of brackets, function arguments, leading signs and `#` indirections
/// together in one value. LinuxCNC's own programs nest a handful of levels; 100 keeps the
/// evaluator's stack below about 100 kB on any line.
pub const MAX_NESTING: usize = 100;

/// An expression error: byte range in the line and message.
#[derive(Debug)]
pub struct ExprError {
    pub span: Range<usize>,
    pub message: String,
    pub label: &'static str,
}

type R<T> = Result<T, ExprError>;

/// A cursor over one line that reads values and expressions.
pub struct Eval<'a> {
    pub line: &'a str,
    pub i: usize,
    pub params: &'a Params,
    /// Fanuc macro B: `ATAN[a,b]` and `#0` (vacant) allowed.
    pub fanuc: bool,
    /// Nesting levels open at the cursor, at most [`MAX_NESTING`].
    depth: usize,
}

const FUNCTIONS: [&str; 14] = [
    "ABS", "ACOS", "ASIN", "ATAN", "COS", "EXISTS", "EXP", "FIX", "FUP", "ROUND", "LN", "SIN",
    "SQRT", "TAN",
];

/// If `line[i..]` starts with a function name followed (after blanks) by `[`, its length.
pub fn function_at(line: &str, i: usize) -> Option<&'static str> {
    let rest = &line.as_bytes()[i..];
    FUNCTIONS.iter().copied().find(|name| {
        rest.len() > name.len()
            && rest[..name.len()].eq_ignore_ascii_case(name.as_bytes())
            && rest[name.len()..]
                .iter()
                .find(|b| !matches!(b, b' ' | b'\t'))
                == Some(&b'[')
    })
}

impl<'a> Eval<'a> {
    /// A cursor at byte `i` of `line`, outside any nesting.
    pub fn new(line: &'a str, i: usize, params: &'a Params, fanuc: bool) -> Eval<'a> {
        Eval {
            line,
            i,
            params,
            fanuc,
            depth: 0,
        }
    }

    /// Runs `inner` one nesting level deeper, refusing the level that opens at byte `at`
    /// when it goes beyond [`MAX_NESTING`].
    fn nested<T>(&mut self, at: usize, inner: impl FnOnce(&mut Self) -> R<T>) -> R<T> {
        if self.depth >= MAX_NESTING {
            let at = at.min(self.line.len());
            return Err(self.err(
                at..(at + 1).min(self.line.len()),
                format!(
                    "expression nested deeper than {MAX_NESTING} levels: expected at most \
                     {MAX_NESTING} brackets, functions, signs and `#` inside one another"
                ),
                "one level too deep",
            ));
        }
        self.depth += 1;
        let result = inner(self);
        self.depth -= 1;
        result
    }

    fn err(
        &self,
        span: Range<usize>,
        message: impl Into<String>,
        label: &'static str,
    ) -> ExprError {
        ExprError {
            span,
            message: message.into(),
            label,
        }
    }

    fn bytes(&self) -> &'a [u8] {
        self.line.as_bytes()
    }

    pub fn skip_blanks(&mut self) {
        while matches!(self.bytes().get(self.i), Some(b' ' | b'\t')) {
            self.i += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.skip_blanks();
        self.bytes().get(self.i).copied()
    }

    fn expect(&mut self, c: u8, what: &str) -> R<()> {
        if self.peek() == Some(c) {
            self.i += 1;
            Ok(())
        } else {
            let at = self.i.min(self.line.len());
            let end = (at + 1).min(self.line.len()).max(at);
            Err(self.err(
                at..end,
                format!("expected `{}` {what}", c as char),
                "expected here",
            ))
        }
    }

    /// A real value: number, `[expr]`, `#param`, function, with optional leading sign.
    pub fn value(&mut self) -> R<f64> {
        let start = self.i;
        let c = self.peek();
        // Where a nesting level opens: the bracket, sign or function name.
        let open = self.i;
        match c {
            Some(b'[') => self.nested(open, |e| {
                e.i += 1;
                let v = e.binary(0)?;
                e.expect(b']', "to close the expression")?;
                Ok(v)
            }),
            Some(b'#') => {
                let p = self.param()?;
                if let (Param::Numbered(n), Some(what)) = (&p, self.params.unmodelled) {
                    if let Some(what) = what(*n) {
                        return Err(self.err(
                            start..self.i,
                            format!("`#{n}` is {what} on this control: mtsim does not model its value, so the program is not read"),
                            "system variable not modelled",
                        ));
                    }
                }
                match self.params.get(&p) {
                    Some(v) => Ok(v),
                    None => Err(self.err(
                        start..self.i,
                        format!(
                            "parameter `{}` is not defined: expected it set before it is read{}",
                            &self.line[start..self.i],
                            match &p {
                                Param::Named(n) if n.starts_with("_hal[") => " (a HAL pin: give its value in the scenario, `[reader] hal_pins = { \"pin.name\" = 1.0 }`)",
                                _ => "",
                            }
                        ),
                        "undefined parameter",
                    )),
                }
            }
            Some(b'-') => self.nested(open, |e| {
                e.i += 1;
                Ok(-e.value()?)
            }),
            Some(b'+') => self.nested(open, |e| {
                e.i += 1;
                e.value()
            }),
            Some(c) if c.is_ascii_alphabetic() => self.nested(open, Self::function),
            Some(c) if c.is_ascii_digit() || c == b'.' => self.number(),
            _ => {
                let at = self.i.min(self.line.len());
                Err(self.err(
                    at..(at + 1).min(self.line.len()),
                    "expected a value: a number, `[expression]`, `#parameter` or a function",
                    "expected a value",
                ))
            }
        }
    }

    fn number(&mut self) -> R<f64> {
        let start = self.i;
        let b = self.bytes();
        let mut i = self.i;
        while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
            i += 1;
        }
        self.i = i;
        let text = &self.line[start..i];
        match text.parse::<f64>() {
            Ok(v) if text.matches('.').count() <= 1 && v.is_finite() => Ok(v),
            _ => Err(self.err(
                start..i,
                format!("malformed number `{text}`: expected digits with at most one `.`"),
                "malformed number",
            )),
        }
    }

    /// `#` followed by a number, `<name>`, `[expr]` or another parameter.
    pub fn param(&mut self) -> R<Param> {
        let start = self.i;
        self.expect(b'#', "")?;
        if self.peek() == Some(b'<') {
            let open = self.i;
            let Some(close) = self.line[open..].find('>') else {
                return Err(self.err(
                    start..self.line.len(),
                    "unclosed parameter name: expected `>` after `#<name`",
                    "no `>`",
                ));
            };
            let name: String = self.line[open + 1..open + close]
                .chars()
                .filter(|c| !c.is_whitespace())
                .map(|c| c.to_ascii_lowercase())
                .collect();
            self.i = open + close + 1;
            if name.is_empty() {
                return Err(self.err(
                    start..self.i,
                    "empty parameter name: expected `#<name>`",
                    "empty name",
                ));
            }
            return Ok(Param::Named(name));
        }
        let v = self.nested(start, Self::value)?;
        if v < 0.0
            || v.fract().abs() > 1e-4
            || v.round() as usize > MAX_PARAMETER
            || (v.round() == 0.0 && !self.fanuc)
        {
            return Err(self.err(
                start..self.i,
                format!("parameter number {v}: expected a whole number 1 to {MAX_PARAMETER}"),
                "bad parameter number",
            ));
        }
        Ok(Param::Numbered(v.round() as usize))
    }

    fn function(&mut self) -> R<f64> {
        let start = self.i;
        let Some(name) = function_at(self.line, self.i) else {
            let b = self.bytes();
            let mut end = self.i;
            while end < b.len() && b[end].is_ascii_alphabetic() {
                end += 1;
            }
            return Err(self.err(
                start..end,
                format!(
                    "unknown function `{}`: expected one of {}",
                    &self.line[start..end],
                    FUNCTIONS.join(" ")
                ),
                "unknown function",
            ));
        };
        self.i += name.len();
        if name == "EXISTS" {
            self.expect(b'[', "after EXISTS")?;
            let p = self.param()?;
            self.expect(b']', "to close EXISTS")?;
            return Ok(if self.params.get(&p).is_some() {
                1.0
            } else {
                0.0
            });
        }
        self.expect(b'[', "after the function name")?;
        let a = self.binary(0)?;
        if name == "ATAN" {
            let b = if self.fanuc && self.peek() == Some(b',') {
                self.i += 1;
                let b = self.binary(0)?;
                self.expect(b']', "to close ATAN")?;
                b
            } else {
                self.expect(b']', "to close ATAN")?;
                self.expect(b'/', "in ATAN[y]/[x]")?;
                if self.peek() != Some(b'[') {
                    return Err(self.err(
                        self.i..self.i,
                        "expected `[x]` after `ATAN[y]/`",
                        "expected `[`",
                    ));
                }
                self.value()?
            };
            return Ok(a.atan2(b).to_degrees());
        }
        self.expect(b']', "to close the function argument")?;
        let span = start..self.i;
        let domain = |ok: bool, what: &str| {
            if ok {
                Ok(())
            } else {
                Err(ExprError {
                    span: span.clone(),
                    message: format!("`{}` of {a}: expected {what}", name),
                    label: "out of domain",
                })
            }
        };
        Ok(match name {
            "ABS" => a.abs(),
            "ACOS" => {
                domain((-1.0..=1.0).contains(&a), "an argument from -1 to 1")?;
                a.acos().to_degrees()
            }
            "ASIN" => {
                domain((-1.0..=1.0).contains(&a), "an argument from -1 to 1")?;
                a.asin().to_degrees()
            }
            "COS" => a.to_radians().cos(),
            "SIN" => a.to_radians().sin(),
            "TAN" => a.to_radians().tan(),
            "EXP" => a.exp(),
            "FIX" => a.floor(),
            "FUP" => a.ceil(),
            "ROUND" => a.round(),
            "LN" => {
                domain(a > 0.0, "an argument greater than zero")?;
                a.ln()
            }
            _ => {
                domain(a >= 0.0, "an argument of zero or more")?;
                a.sqrt()
            }
        })
    }

    /// The binary operator at the cursor, its length and precedence.
    fn operator(&mut self) -> Option<(Op, usize, u8)> {
        let rest = &self.line.as_bytes()[self.i..];
        let kw =
            |k: &str| rest.len() >= k.len() && rest[..k.len()].eq_ignore_ascii_case(k.as_bytes());
        self.skip_blanks();
        let rest = &self.line.as_bytes()[self.i..];
        let kw2 =
            |k: &str| rest.len() >= k.len() && rest[..k.len()].eq_ignore_ascii_case(k.as_bytes());
        let _ = kw;
        let ops: [(&str, Op, u8); 15] = [
            ("**", Op::Pow, 4),
            ("*", Op::Mul, 3),
            ("/", Op::Div, 3),
            ("MOD", Op::Mod, 3),
            ("+", Op::Add, 2),
            ("-", Op::Sub, 2),
            ("EQ", Op::Eq, 1),
            ("NE", Op::Ne, 1),
            ("GT", Op::Gt, 1),
            ("GE", Op::Ge, 1),
            ("LT", Op::Lt, 1),
            ("LE", Op::Le, 1),
            ("AND", Op::And, 0),
            ("OR", Op::Or, 0),
            ("XOR", Op::Xor, 0),
        ];
        ops.iter()
            .find(|(k, _, _)| kw2(k))
            .map(|&(k, op, prec)| (op, k.len(), prec))
    }

    /// An expression of operators of precedence `min` and higher.
    pub fn binary(&mut self, min: u8) -> R<f64> {
        let mut lhs = self.value()?;
        loop {
            let Some((op, len, prec)) = self.operator() else {
                return Ok(lhs);
            };
            if prec < min {
                return Ok(lhs);
            }
            let at = self.i;
            self.i += len;
            let rhs = self.binary(prec + 1)?;
            lhs = op
                .apply(lhs, rhs)
                .map_err(|m| self.err(at..at + len, m, "arithmetic error"))?;
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Op {
    Pow,
    Mul,
    Div,
    Mod,
    Add,
    Sub,
    Eq,
    Ne,
    Gt,
    Ge,
    Lt,
    Le,
    And,
    Or,
    Xor,
}

impl Op {
    fn apply(self, a: f64, b: f64) -> Result<f64, String> {
        let t = |c: bool| if c { 1.0 } else { 0.0 };
        let v = match self {
            Op::Pow => {
                if a < 0.0 && b.fract() != 0.0 {
                    return Err(format!(
                        "{a} ** {b}: expected a whole exponent for a negative base"
                    ));
                }
                a.powf(b)
            }
            Op::Mul => a * b,
            Op::Div => {
                if b == 0.0 {
                    return Err("division by zero: expected a divisor other than 0".into());
                }
                a / b
            }
            Op::Mod => {
                if b == 0.0 {
                    return Err("MOD by zero: expected a divisor other than 0".into());
                }
                // LinuxCNC: result has the sign of the divisor... fmod then shifted positive.
                let r = a % b;
                if r < 0.0 {
                    r + b.abs()
                } else {
                    r
                }
            }
            Op::Add => a + b,
            Op::Sub => a - b,
            Op::Eq => t(a == b),
            Op::Ne => t(a != b),
            Op::Gt => t(a > b),
            Op::Ge => t(a >= b),
            Op::Lt => t(a < b),
            Op::Le => t(a <= b),
            Op::And => t(a != 0.0 && b != 0.0),
            Op::Or => t(a != 0.0 || b != 0.0),
            Op::Xor => t((a != 0.0) != (b != 0.0)),
        };
        if v.is_finite() {
            Ok(v)
        } else {
            Err(format!("result {v} is not finite: expected a finite value"))
        }
    }
}
