//! Sinumerik arithmetic: R parameters, `DEF` variables, operators and functions, read from
//! an upper-cased block (byte offsets are those of the source line).
//!
//! Precedence, highest first (Job planning, "Arithmetic functions" / "Precedence of
//! operations"): `NOT`; `*` `/` `DIV` `MOD`; `+` `-`; `B_AND`; `B_XOR`; `B_OR`; `AND`;
//! `XOR`; `OR`; the comparisons `==` `<>` `<` `>` `<=` `>=` (so `(R1>0) AND (R2>0)` needs
//! its parentheses, as on the control). Angles are in degrees; `TRUE` is 1, `FALSE` 0.

use std::collections::HashMap;

use crate::lex::{LineError, LineResult};

/// R parameters a program may use: `R0`-`R999`.
pub(super) const R_COUNT: usize = 1000;
/// Deepest nesting of parentheses and function calls in one expression.
const MAX_DEPTH: usize = 32;

/// The variables a block reads and writes: R parameters (global) and the `DEF` variables
/// of each program level (the last map is the running level's).
pub(super) struct Vars {
    pub r: Vec<f64>,
    /// The system variables' values the options give (`Options::system_variables`).
    pub system: Vec<(String, f64)>,
    pub levels: Vec<HashMap<String, f64>>,
}

impl Vars {
    pub fn new() -> Vars {
        Vars {
            r: vec![0.0; R_COUNT],
            system: Vec::new(),
            levels: vec![HashMap::new()],
        }
    }

    /// The running level's variable `name` (an array element is held under its key
    /// `NAME[i]` or `NAME[i,j]`, see [`element_key`]).
    pub fn get(&self, name: &str) -> Option<f64> {
        self.levels.last().and_then(|l| l.get(name)).copied()
    }

    /// Whether `name` is an array of the running level (its first element exists).
    pub fn is_array(&self, name: &str) -> bool {
        (1..=MAX_DIMS).any(|n| self.get(&element_key(name, &[0; MAX_DIMS][..n])).is_some())
    }
}

/// Most dimensions of a `DEF` array (Sinumerik: up to three).
pub(super) const MAX_DIMS: usize = 3;

/// The key an array element is held under: `NAME[i]`, `NAME[i,j]`, `NAME[i,j,k]`.
pub(super) fn element_key(name: &str, index: &[usize]) -> String {
    let list: Vec<String> = index.iter().map(usize::to_string).collect();
    format!("{name}[{}]", list.join(","))
}

/// The indices `[i, j …]` after an array's name (the cursor on `[`): each a whole number
/// from 0, at most [`MAX_DIMS`] of them.
pub(super) fn indices(sc: &mut Scan, vars: &Vars, at: usize) -> LineResult<Vec<usize>> {
    sc.eat(b'[');
    let mut out = Vec::new();
    loop {
        let k = expr(sc, vars)?;
        if !(k >= 0.0 && k.fract() == 0.0 && k < 1e9) {
            return Err(sc.err(
                at,
                format!("array index {k}: expected a whole number from 0"),
                "bad index",
            ));
        }
        out.push(k as usize);
        if sc.eat(b']') {
            break;
        }
        if out.len() == MAX_DIMS || !sc.eat(b',') {
            return Err(sc.err(
                at,
                format!("expected `]` (or `,` and the next of at most {MAX_DIMS} indices)"),
                "unclosed `[`",
            ));
        }
    }
    Ok(out)
}

/// The refusal of a name the program reads or sets without defining it.
pub(super) fn undefined(sc: &Scan, at: usize, name: &str) -> LineError {
    sc.err(
        at,
        format!("`{name}` is not defined in this program: a global user variable (GUD) or a name from a definition file, which is not given (mtsim reads no GUD files); expected `DEF REAL {name}` (or INT, BOOL) before it is used"),
        "undefined variable",
    )
}

/// An array element the program reads or sets: its key, or the refusal (the name is no
/// array of the program, or the index lies outside it).
pub(super) fn element(sc: &mut Scan, vars: &Vars, name: &str, at: usize) -> LineResult<String> {
    let index = indices(sc, vars, at)?;
    let key = element_key(name, &index);
    if vars.get(&key).is_some() {
        return Ok(key);
    }
    if !vars.is_array(name) {
        return Err(undefined(sc, at, name));
    }
    Err(sc.err(
        at,
        format!("`{key}`: the index lies outside the array `{name}` as DEF gives it"),
        "index out of range",
    ))
}

/// A cursor over one upper-cased block.
pub(super) struct Scan<'a> {
    pub s: &'a [u8],
    pub at: usize,
}

impl<'a> Scan<'a> {
    pub fn new(s: &'a str) -> Scan<'a> {
        Scan {
            s: s.as_bytes(),
            at: 0,
        }
    }

    pub fn blanks(&mut self) {
        while matches!(self.s.get(self.at), Some(b' ' | b'\t')) {
            self.at += 1;
        }
    }

    /// The next byte after blanks.
    pub fn peek(&mut self) -> Option<u8> {
        self.blanks();
        self.s.get(self.at).copied()
    }

    /// At the end of the block or at a `;` comment.
    pub fn done(&mut self) -> bool {
        matches!(self.peek(), None | Some(b';'))
    }

    /// Takes `c` when it is next.
    pub fn eat(&mut self, c: u8) -> bool {
        if self.peek() == Some(c) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    /// Takes the two bytes `t` when they are next.
    fn eat2(&mut self, t: &[u8; 2]) -> bool {
        self.blanks();
        if self.s[self.at..].starts_with(t) {
            self.at += 2;
            true
        } else {
            false
        }
    }

    /// Takes keyword `k` when it is next as a whole word.
    pub fn keyword(&mut self, k: &str) -> bool {
        self.blanks();
        let end = self.at + k.len();
        if self.s[self.at..].starts_with(k.as_bytes())
            && !self.s.get(end).is_some_and(|c| is_ident(*c))
        {
            self.at = end;
            true
        } else {
            false
        }
    }

    /// An identifier `[A-Z_$][A-Z0-9_]*` and its start; `None` (nothing taken) otherwise.
    pub fn ident(&mut self) -> Option<(&'a str, usize)> {
        self.blanks();
        let start = self.at;
        if !self
            .s
            .get(start)
            .is_some_and(|c| c.is_ascii_uppercase() || *c == b'_' || *c == b'$')
        {
            return None;
        }
        let mut end = start + 1;
        while self.s.get(end).is_some_and(|c| is_ident(*c)) {
            end += 1;
        }
        self.at = end;
        Some((
            std::str::from_utf8(&self.s[start..end]).unwrap_or(""),
            start,
        ))
    }

    /// An unsigned number as written (`12`, `1.5`, `.5`, `3.`, `1E-3` is not Sinumerik).
    pub fn number(&mut self) -> Option<(&'a str, f64)> {
        self.blanks();
        let start = self.at;
        let mut end = start;
        while self
            .s
            .get(end)
            .is_some_and(|c| c.is_ascii_digit() || *c == b'.')
        {
            end += 1;
        }
        // `EX` exponent: 1.5EX3 = 1500.
        let text = std::str::from_utf8(&self.s[start..end]).ok()?;
        let mut v: f64 = text.parse().ok()?;
        self.at = end;
        if self.s[end..].starts_with(b"EX") {
            let mut k = end + 2;
            let neg = self.s.get(k) == Some(&b'-');
            if matches!(self.s.get(k), Some(b'-' | b'+')) {
                k += 1;
            }
            let e0 = k;
            while self.s.get(k).is_some_and(|c| c.is_ascii_digit()) {
                k += 1;
            }
            if let Ok(e) = std::str::from_utf8(&self.s[e0..k])
                .unwrap_or("")
                .parse::<i32>()
            {
                v *= 10f64.powi(if neg { -e } else { e });
                self.at = k;
            }
        }
        Some((text, v))
    }

    pub fn err(&self, from: usize, message: impl Into<String>, label: &str) -> LineError {
        let end = (self.at.max(from + 1)).min(self.s.len().max(from));
        LineError::new(from..end, message, label)
    }
}

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// Evaluates one expression at the cursor.
pub(super) fn expr(sc: &mut Scan, vars: &Vars) -> LineResult<f64> {
    let at = sc.at;
    let v = Eval { vars, depth: 0 }.comparison(sc)?;
    if !v.is_finite() {
        return Err(sc.err(
            at,
            "the value overflows: expected a finite number",
            "not finite",
        ));
    }
    Ok(v)
}

struct Eval<'v> {
    vars: &'v Vars,
    depth: usize,
}

type Binary = fn(f64, f64) -> f64;

/// The binary operator levels below the comparisons, loosest first.
const LEVELS: [&[(&str, Binary)]; 7] = [
    &[("OR", |a, b| truth(a != 0.0 || b != 0.0))],
    &[("XOR", |a, b| truth((a != 0.0) != (b != 0.0)))],
    &[("AND", |a, b| truth(a != 0.0 && b != 0.0))],
    &[("B_OR", |a, b| (a as i64 | b as i64) as f64)],
    &[("B_XOR", |a, b| (a as i64 ^ b as i64) as f64)],
    &[("B_AND", |a, b| (a as i64 & b as i64) as f64)],
    &[("+", |a, b| a + b), ("-", |a, b| a - b)],
];

fn truth(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}

impl Eval<'_> {
    fn comparison(&mut self, sc: &mut Scan) -> LineResult<f64> {
        let a = self.level(sc, 0)?;
        type Compare = fn(f64, f64) -> bool;
        let ops: [(&[u8; 2], Compare); 4] = [
            (b"==", |a, b| a == b),
            (b"<>", |a, b| a != b),
            (b"<=", |a, b| a <= b),
            (b">=", |a, b| a >= b),
        ];
        for (t, f) in ops {
            if sc.eat2(t) {
                let b = self.level(sc, 0)?;
                return Ok(truth(f(a, b)));
            }
        }
        if sc.eat(b'<') {
            let b = self.level(sc, 0)?;
            return Ok(truth(a < b));
        }
        if sc.eat(b'>') {
            let b = self.level(sc, 0)?;
            return Ok(truth(a > b));
        }
        Ok(a)
    }

    fn level(&mut self, sc: &mut Scan, k: usize) -> LineResult<f64> {
        if k == LEVELS.len() {
            return self.product(sc);
        }
        let mut a = self.level(sc, k + 1)?;
        'more: loop {
            for (name, f) in LEVELS[k] {
                let hit = if name.len() == 1 {
                    sc.eat(name.as_bytes()[0])
                } else {
                    sc.keyword(name)
                };
                if hit {
                    let b = self.level(sc, k + 1)?;
                    a = f(a, b);
                    continue 'more;
                }
            }
            return Ok(a);
        }
    }

    fn product(&mut self, sc: &mut Scan) -> LineResult<f64> {
        let mut a = self.unary(sc)?;
        loop {
            let at = sc.at;
            if sc.eat(b'*') {
                a *= self.unary(sc)?;
            } else if sc.eat(b'/') {
                let b = self.unary(sc)?;
                if b == 0.0 {
                    return Err(sc.err(at, "division by zero", "divided by zero"));
                }
                a /= b;
            } else if sc.keyword("DIV") {
                let b = self.unary(sc)?;
                if b.trunc() == 0.0 {
                    return Err(sc.err(at, "DIV by zero", "divided by zero"));
                }
                a = (a.trunc() / b.trunc()).trunc();
            } else if sc.keyword("MOD") {
                let b = self.unary(sc)?;
                if b == 0.0 {
                    return Err(sc.err(at, "MOD by zero", "divided by zero"));
                }
                a %= b;
            } else {
                return Ok(a);
            }
        }
    }

    /// A sign or `NOT` before an operand; each counts as a level of nesting.
    fn unary(&mut self, sc: &mut Scan) -> LineResult<f64> {
        let at = sc.at;
        let op = if sc.eat(b'-') {
            b'-'
        } else if sc.eat(b'+') {
            b'+'
        } else if sc.keyword("NOT") {
            b'!'
        } else if sc.keyword("B_NOT") {
            b'~'
        } else {
            return self.operand(sc);
        };
        self.deeper(sc, at)?;
        let v = self.unary(sc)?;
        self.depth -= 1;
        Ok(match op {
            b'-' => -v,
            b'!' => truth(v == 0.0),
            b'~' => !(v as i64) as f64,
            _ => v,
        })
    }

    /// One level deeper, bounded to [`MAX_DEPTH`].
    fn deeper(&mut self, sc: &Scan, at: usize) -> LineResult<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(sc.err(
                at,
                format!("expression nested deeper than {MAX_DEPTH} levels"),
                "too deep",
            ));
        }
        Ok(())
    }

    fn nested(&mut self, sc: &mut Scan, at: usize) -> LineResult<f64> {
        self.deeper(sc, at)?;
        let v = self.comparison(sc);
        self.depth -= 1;
        v
    }

    fn operand(&mut self, sc: &mut Scan) -> LineResult<f64> {
        let at = {
            sc.blanks();
            sc.at
        };
        if sc.eat(b'(') {
            let v = self.nested(sc, at)?;
            return close(sc, at).map(|_| v);
        }
        if let Some((_, v)) = sc.number() {
            return Ok(v);
        }
        let Some((name, at)) = sc.ident() else {
            return Err(sc.err(
                at,
                "expected a number, a variable, `(` or a function",
                "expected a value",
            ));
        };
        if name.starts_with('$') {
            return self.system_variable(sc, name, at);
        }
        if let Some(v) = r_parameter(name) {
            return self.r_value(sc, v, at);
        }
        if name == "R" && sc.eat(b'[') {
            let k = self.nested(sc, at)?;
            if !sc.eat(b']') {
                return Err(sc.err(
                    at,
                    "expected `]` after the R parameter's index",
                    "unclosed `[`",
                ));
            }
            return self.r_value(sc, Some(k), at);
        }
        match name {
            "TRUE" => return Ok(1.0),
            "FALSE" => return Ok(0.0),
            "PI" | "$PI" => return Ok(std::f64::consts::PI),
            _ => {}
        }
        if sc.peek() == Some(b'(') {
            return self.function(sc, name, at);
        }
        if sc.peek() == Some(b'[') {
            let key = element(sc, self.vars, name, at)?;
            return Ok(self.vars.get(&key).unwrap_or(0.0));
        }
        self.vars.get(name).ok_or_else(|| undefined(sc, at, name))
    }

    /// `ISVAR("NAME")`: TRUE when the program has defined the variable (mtsim reads no GUD
    /// files, so a global user variable is not one); `GETT(…)`: the T number of a named
    /// tool, refused (tool management is not modelled), after its argument is read so that
    /// an undefined name is named first.
    fn special(&mut self, sc: &mut Scan, name: &str, at: usize) -> LineResult<f64> {
        sc.eat(b'(');
        sc.blanks();
        let text = if sc.eat(b'"') {
            let from = sc.at;
            while sc.s.get(sc.at).is_some_and(|c| *c != b'"') {
                sc.at += 1;
            }
            let text = String::from_utf8_lossy(&sc.s[from..sc.at])
                .trim()
                .to_string();
            if !sc.eat(b'"') {
                return Err(sc.err(at, "expected `\"` to close the text", "unclosed text"));
            }
            Some(text)
        } else {
            None
        };
        if text.is_none() {
            self.nested(sc, at)?;
        }
        while sc.eat(b',') {
            self.nested(sc, at)?;
        }
        close(sc, at)?;
        match (name, text) {
            ("ISVAR", Some(v)) => Ok(truth(
                self.vars.get(&v).is_some() || self.vars.is_array(&v) || r_parameter(&v).is_some(),
            )),
            ("ISVAR", None) => Err(sc.err(
                at,
                "`ISVAR` takes the variable's name as text: expected ISVAR(\"NAME\")",
                "ISVAR",
            )),
            _ => Err(sc.err(
                at,
                "`GETT` (the T number of a tool given by name, Sinumerik tool management) is not supported by mtsim: the control's tool list is not given",
                "tool management",
            )),
        }
    }

    fn r_value(&self, sc: &Scan, k: Option<f64>, at: usize) -> LineResult<f64> {
        let index = k.filter(|k| *k >= 0.0 && k.fract() == 0.0 && *k < R_COUNT as f64);
        index.map(|k| self.vars.r[k as usize]).ok_or_else(|| {
            sc.err(
                at,
                format!("R parameter out of range: expected R0 to R{}", R_COUNT - 1),
                "no such R parameter",
            )
        })
    }

    fn function(&mut self, sc: &mut Scan, name: &str, at: usize) -> LineResult<f64> {
        const NAMES: [&str; 16] = [
            "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN2", "SQRT", "ABS", "POT", "TRUNC", "ROUND",
            "ROUNDUP", "LN", "EXP", "MINVAL", "MAXVAL",
        ];
        if name == "ISVAR" || name == "GETT" {
            return self.special(sc, name, at);
        }
        if matches!(
            name,
            "DC" | "ACP" | "ACN" | "CAC" | "CIC" | "CACP" | "CACN" | "CDC"
        ) {
            return Err(sc.err(
                at,
                format!("`{name}(..)` (a rotary axis position approached the shortest way, or in the positive or negative direction, as a modulo axis; Fundamentals, \"Absolute dimensions for rotary axes (DC, ACP, ACN)\") is not supported by mtsim: its rotary axes are not modulo axes, so the way round is not known"),
                "rotary axis positioning",
            ));
        }
        if !NAMES.contains(&name) {
            return Err(sc.err(
                at,
                format!(
                    "function `{name}` is not supported by mtsim: expected {}",
                    NAMES.join(" ")
                ),
                "unsupported function",
            ));
        }
        sc.eat(b'(');
        let mut args = [0.0; 2];
        let mut n = 0;
        if !sc.eat(b')') {
            loop {
                let v = self.nested(sc, at)?;
                if n == args.len() {
                    return Err(sc.err(
                        at,
                        format!("too many arguments to `{name}`"),
                        "too many arguments",
                    ));
                }
                args[n] = v;
                n += 1;
                if sc.eat(b')') {
                    break;
                }
                if !sc.eat(b',') {
                    return Err(sc.err(
                        at,
                        format!("expected `,` or `)` in the arguments of `{name}`"),
                        "unclosed call",
                    ));
                }
            }
        }
        let [a, b] = args;
        let (want, v) = match name {
            "SIN" => (1, a.to_radians().sin()),
            "COS" => (1, a.to_radians().cos()),
            "TAN" => (1, a.to_radians().tan()),
            "ASIN" => (1, a.asin().to_degrees()),
            "ACOS" => (1, a.acos().to_degrees()),
            "ATAN2" => (2, a.atan2(b).to_degrees()),
            "SQRT" => (1, a.sqrt()),
            "ABS" => (1, a.abs()),
            "POT" => (1, a * a),
            "TRUNC" => (1, a.trunc()),
            "ROUND" => (1, a.round()),
            "ROUNDUP" => (
                1,
                if a.fract() == 0.0 {
                    a
                } else {
                    a.trunc() + a.signum()
                },
            ),
            "LN" => (1, a.ln()),
            "EXP" => (1, a.exp()),
            "MINVAL" => (2, a.min(b)),
            "MAXVAL" => (2, a.max(b)),
            _ => (0, 0.0),
        };
        if n != want {
            return Err(sc.err(
                at,
                format!("`{name}` takes {want} argument(s), given {n}"),
                "wrong argument count",
            ));
        }
        if !v.is_finite() {
            return Err(sc.err(
                at,
                format!("`{name}` of an argument outside its domain"),
                "not a number",
            ));
        }
        Ok(v)
    }
}

/// `Some(Some(n))` for `Rn` (an R parameter written with its number), `None` otherwise.
pub(super) fn r_parameter(name: &str) -> Option<Option<f64>> {
    let digits = name.strip_prefix('R')?;
    (!digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
        .then(|| digits.parse::<f64>().ok())
}

fn close(sc: &mut Scan, at: usize) -> LineResult<()> {
    if sc.eat(b')') {
        Ok(())
    } else {
        Err(sc.err(at, "expected `)` to close this `(`", "unclosed `(`"))
    }
}

impl Eval<'_> {
    /// A system variable's value (the cursor after its name): one the options give (with
    /// its indices, `$A_DBB[10]`), one mtsim knows ([`system_value`]), or a refusal that
    /// names it and says where its value goes.
    fn system_variable(&mut self, sc: &mut Scan, name: &str, at: usize) -> LineResult<f64> {
        let mut key = name.to_string();
        if sc.peek() == Some(b'[') {
            // Indices that are numbers make the key; others (`[1,X,TR]`: an axis and a
            // component) leave the variable named as a whole.
            let before = sc.at;
            match indices(sc, self.vars, at) {
                Ok(index) => key = element_key(name, &index),
                Err(_) => sc.at = before,
            }
        }
        if let Some((_, v)) = self.vars.system.iter().find(|(k, _)| *k == key) {
            return Ok(*v);
        }
        if let Some(v) = system_value(&key) {
            return Ok(v);
        }
        Err(sc.err(
            at,
            format!(
                "system variable `{key}` ({}): its value is the control's, and it is not given",
                system_variable_kind(name)
            ),
            "system variable",
        )
        .help(format!("give the value the control holds in the scenario's [reader] system_variables, e.g. {{ \"{key}\" = 0.0 }} (docs/scenario-format.md)")))
    }
}

/// The system variables mtsim gives a value (SINUMERIK 840D sl "System variables" list
/// manual): `$MN_SCALING_SYSTEM_IS_METRIC` (MD10240) is 1, as every mtsim machine file is
/// in mm (docs/machine-format.md); `$P_SEARCH` (block search active) is 0, as mtsim runs
/// a program from its first block; `$P_MC` (a subprogram runs as a macro call, an M
/// function's replacement) is 0, as mtsim replaces no M function by a subprogram.
fn system_value(name: &str) -> Option<f64> {
    match name {
        "$MN_SCALING_SYSTEM_IS_METRIC" => Some(1.0),
        "$P_SEARCH" | "$P_MC" => Some(0.0),
        _ => None,
    }
}

/// What a Sinumerik system variable is, by its prefix (SINUMERIK 840D sl "System
/// variables" list manual: `$M…` machine data, `$S…` setting data, `$P…` program
/// variables read at preprocessing, `$A…` main-run variables, `$T…` tool data), for the
/// refusal that names it.
pub(super) fn system_variable_kind(name: &str) -> &'static str {
    let upper = name.to_ascii_uppercase();
    let kinds: [(&str, &str); 12] = [
        ("$MN_", "general machine data"),
        ("$MC_", "channel machine data"),
        ("$MA_", "axis machine data"),
        ("$SN_", "general setting data"),
        ("$SC_", "channel setting data"),
        ("$SA_", "axis setting data"),
        ("$P_UIFR", "a settable zero offset frame (G54 …)"),
        ("$P_", "a program variable read at preprocessing"),
        ("$AA_", "an axis main-run variable"),
        ("$A_DB", "PLC data (a data block byte, word or double word)"),
        (
            "$A_",
            "a main-run variable (time, PLC signals, measurement)",
        ),
        ("$TC_", "tool management data"),
    ];
    kinds.iter().find(|(p, _)| upper.starts_with(p)).map_or(
        "a system variable of the control; the SINUMERIK system variables list manual names it",
        |(_, k)| k,
    )
}
