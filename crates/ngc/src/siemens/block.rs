//! One Sinumerik block: block number and label, then a statement (`IF`, `WHILE`, `FOR`,
//! `REPEAT`, `LOOP`, `GOTOx`, `DEF`, `PROC`, `RET`, `MCALL`, a frame) or a list of words,
//! names and calls (Fundamentals, "Structure of an NC program"; Job planning, "Flexible NC
//! programming").

use super::expr::{
    element, element_key, expr, indices, r_parameter, system_variable_kind, undefined, Scan,
};
use super::flow::skip_number_and_label;
use super::frame::{rotation_zyx, Instruction};
use super::keywords::{NOTED, REFUSED};
use super::state::{Structure, Var};
use super::words::Words;
use super::Reader;
use crate::lex::LineResult;

/// Most variables (array elements counted) one program level holds.
const MAX_VARIABLES: usize = 10_000;

impl Reader {
    /// Runs one upper-cased line; `Ok(false)` when the program ends.
    pub(super) fn block(&mut self, up: &str, line_no: usize) -> LineResult<bool> {
        let mut sc = Scan::new(up);
        match sc.peek() {
            // Block skip (the skip switch on, as the G-code reader), and `%_N_..` headers.
            Some(b'/' | b'%') | None | Some(b';') => return Ok(true),
            _ => {}
        }
        skip_number_and_label(&mut sc);
        if sc.done() {
            return Ok(true);
        }
        let save = sc.at;
        if let Some((kw, at)) = sc.ident() {
            if let Some(go_on) = self.statement(kw, at, &mut sc, line_no)? {
                return Ok(go_on);
            }
        }
        sc.at = save;
        let mut w = Words::default();
        self.collect(&mut sc, &mut w, line_no)?;
        self.emit(w, up, line_no)
    }

    /// The statement `kw` (at byte `at`), when it is one.
    fn statement(
        &mut self,
        kw: &str,
        at: usize,
        sc: &mut Scan,
        line_no: usize,
    ) -> LineResult<Option<bool>> {
        let span = at..sc.at;
        match kw {
            "IF" => self.if_statement(sc, at)?,
            "ELSE" => {
                self.pop(|s| matches!(s, Structure::If), "ELSE", span.clone())?;
                self.skip(false, span)?;
            }
            "ENDIF" => {
                self.pop(|s| matches!(s, Structure::If), "ENDIF", span)?;
            }
            "WHILE" => {
                let (offset, line) = self.line_start;
                if expr(sc, &self.vars)? != 0.0 {
                    self.open(Structure::While { offset, line }, span)?;
                } else {
                    self.skip(false, span)?;
                }
            }
            "ENDWHILE" | "ENDLOOP" => self.close_loop(kw, true, span)?,
            "FOR" => self.for_statement(sc, at)?,
            "ENDFOR" => self.end_for(span)?,
            "REPEATB" => self.section_repeat(kw, sc, at)?,
            "REPEAT" if !sc.done() => self.section_repeat(kw, sc, at)?,
            "REPEAT" | "LOOP" => {
                let level = self.level();
                let (offset, line) = (level.offset, level.line);
                let s = if kw == "LOOP" {
                    Structure::Loop { offset, line }
                } else {
                    Structure::Repeat { offset, line }
                };
                self.open(s, span)?;
            }
            "UNTIL" => {
                let done = expr(sc, &self.vars)? != 0.0;
                self.close_loop(kw, !done, span)?;
            }
            "GOTOF" | "GOTOB" | "GOTO" | "GOTOC" => {
                let Some((target, t_at)) = sc.ident() else {
                    return Err(sc.err(
                        at,
                        format!("{kw} without a target: expected a label or block number"),
                        "no target",
                    ));
                };
                self.jump(kw, target, t_at..sc.at)?;
            }
            "DEF" => self.def(sc, at, line_no)?,
            "DEFINE" => self.define(sc, at)?,
            "PROC" => self.proc(sc, at)?,
            "RET" => return self.end_of_level().map(Some),
            "EXTERN" => {}
            "MCALL" => self.mcall(sc, at, line_no)?,
            "TRANS" | "ATRANS" | "ROT" | "AROT" | "SCALE" | "ASCALE" | "MIRROR" | "AMIRROR" => {
                self.frame_statement(kw, sc, at)?
            }
            "CALL" if sc.peek() == Some(b'"') => {
                // Indirect call of a program named by a string (SINUMERIK programming
                // manual, "Indirect subprogram call CALL"): its name is the path's last
                // part, `_N_NAME_SPF` in the control's internal form.
                let start = sc.at + 1;
                let end = sc.s[start..]
                    .iter()
                    .position(|&c| c == b'"')
                    .map(|k| start + k)
                    .ok_or_else(|| sc.err(at, "`CALL \"` without its closing quote", "unclosed"))?;
                let path = String::from_utf8_lossy(&sc.s[start..end]).into_owned();
                sc.at = end + 1;
                let last = path.rsplit('/').next().unwrap_or(&path);
                let name = last.strip_prefix("_N_").unwrap_or(last);
                let name = name
                    .strip_suffix("_SPF")
                    .or_else(|| name.strip_suffix("_MPF"))
                    .or_else(|| name.rsplit_once('.').map(|(n, _)| n))
                    .unwrap_or(name)
                    .to_string();
                self.call(&name, Vec::new(), 1, at..sc.at)?;
            }
            "CASE" => self.case_statement(sc, at)?,
            "CALL" | "PCALL" | "EXECUTE" | "EXECTAB" | "SETAL" | "STOPRE_" | "WHEN" | "EVERY"
            | "ID" | "IDS" => {
                return Err(sc.err(
                    at,
                    format!("`{kw}` is not supported by mtsim's Siemens reader"),
                    "unsupported statement",
                ));
            }
            _ => return Ok(None),
        }
        Ok(Some(true))
    }

    /// Pops the innermost structure, which must satisfy `is`.
    fn pop(
        &mut self,
        is: impl Fn(&Structure) -> bool,
        kw: &str,
        span: std::ops::Range<usize>,
    ) -> LineResult<Structure> {
        let level = self.level();
        level.opened.pop();
        match level.structures.pop() {
            Some(s) if is(&s) => Ok(s),
            _ => Err(crate::lex::LineError::new(
                span,
                format!("{kw} without its opening statement"),
                "unmatched",
            )),
        }
    }

    /// Closes the loop `kw` ends (`ENDWHILE`, `UNTIL`, `ENDLOOP`); when `again`, counts a
    /// backward jump and goes back: to the `WHILE` line (which opens the loop again), or
    /// to the first line of a `REPEAT` or `LOOP` body (the loop kept open).
    fn close_loop(
        &mut self,
        kw: &str,
        again: bool,
        span: std::ops::Range<usize>,
    ) -> LineResult<()> {
        let opens = |s: &Structure| {
            matches!(
                (kw, s),
                ("ENDWHILE", Structure::While { .. })
                    | ("UNTIL", Structure::Repeat { .. })
                    | ("ENDLOOP", Structure::Loop { .. })
            )
        };
        let head = self.level().opened.last().cloned();
        let s = self.pop(opens, kw, span.clone())?;
        if !again {
            return Ok(());
        }
        let (Structure::While { offset, line }
        | Structure::Repeat { offset, line }
        | Structure::Loop { offset, line }) = s
        else {
            unreachable!("`opens` admits loops only")
        };
        self.backward(span.clone());
        if !matches!(s, Structure::While { .. }) {
            let head = head.unwrap_or((self.line_start.0, self.line_start.1, span));
            self.reopen(s, head);
        }
        (self.level().offset, self.level().line) = (offset, line);
        Ok(())
    }

    /// `IF cond GOTOx label` (a jump) or `IF cond` (a structure).
    fn if_statement(&mut self, sc: &mut Scan, at: usize) -> LineResult<()> {
        let cond = expr(sc, &self.vars)? != 0.0;
        let save = sc.at;
        if let Some((kind, k_at)) = sc.ident().filter(|(k, _)| k.starts_with("GOTO")) {
            let Some((target, t_at)) = sc.ident() else {
                return Err(sc.err(k_at, format!("{kind} without a target"), "no target"));
            };
            if cond {
                self.jump(kind, target, t_at..sc.at)?;
            }
            return Ok(());
        }
        sc.at = save;
        // A false head skips to its ELSE (whose branch then runs) or past its ENDIF.
        if cond || self.skip(true, at..at + 2)? == "ELSE" {
            self.open(Structure::If, at..at + 2)
        } else {
            Ok(())
        }
    }

    /// `FOR var = start TO end`.
    fn for_statement(&mut self, sc: &mut Scan, at: usize) -> LineResult<()> {
        let var = self.variable(sc, at)?;
        if !sc.eat(b'=') {
            return Err(sc.err(at, "expected `FOR var = start TO end`", "FOR"));
        }
        let start = expr(sc, &self.vars)?;
        if !sc.keyword("TO") {
            return Err(sc.err(at, "expected `TO` in `FOR var = start TO end`", "no TO"));
        }
        let end = expr(sc, &self.vars)?;
        self.set(var.clone(), start, sc, at)?;
        if start <= end {
            let level = self.level();
            let (offset, line) = (level.offset, level.line);
            self.open(
                Structure::For {
                    offset,
                    line,
                    var,
                    end,
                },
                at..at + 3,
            )
        } else {
            self.skip(false, at..at + 3).map(|_| ())
        }
    }

    fn end_for(&mut self, span: std::ops::Range<usize>) -> LineResult<()> {
        let head = self.level().opened.last().cloned();
        let Structure::For {
            offset,
            line,
            var,
            end,
        } = self.pop(
            |s| matches!(s, Structure::For { .. }),
            "ENDFOR",
            span.clone(),
        )?
        else {
            unreachable!()
        };
        let v = match &var {
            Var::R(k) => self.vars.r[*k],
            Var::Named(n) => self.vars.get(n).unwrap_or(f64::INFINITY),
        } + 1.0;
        let sc = Scan::new("");
        self.set(var.clone(), v, &sc, 0).map_err(|mut e| {
            e.span = span.clone();
            e
        })?;
        if v <= end {
            self.backward(span.clone());
            let head = head.unwrap_or((self.line_start.0, self.line_start.1, span));
            self.reopen(
                Structure::For {
                    offset,
                    line,
                    var,
                    end,
                },
                head,
            );
            (self.level().offset, self.level().line) = (offset, line);
        }
        Ok(())
    }

    /// An R parameter or `DEF` variable to assign.
    fn variable(&mut self, sc: &mut Scan, at: usize) -> LineResult<Var> {
        let Some((name, n_at)) = sc.ident() else {
            return Err(sc.err(
                at,
                "expected a variable (an R parameter or a DEF variable)",
                "no variable",
            ));
        };
        if let Some(Some(k)) = r_parameter(name) {
            return Ok(Var::R(k as usize));
        }
        if sc.peek() == Some(b'[') {
            return Ok(Var::Named(element(sc, &self.vars, name, n_at)?));
        }
        if self.vars.get(name).is_none() {
            return Err(undefined(sc, n_at, name));
        }
        Ok(Var::Named(name.to_string()))
    }

    /// `DEF REAL|INT|BOOL name[=value], ...`; `DEF STRING|CHAR|AXIS|FRAME …` accepted with
    /// a notice (text, axis names and frames for display or for constructs mtsim refuses
    /// where they are used: a later use of the variable is an undefined variable).
    fn def(&mut self, sc: &mut Scan, at: usize, line_no: usize) -> LineResult<()> {
        let Some((ty, t_at)) = sc.ident() else {
            return Err(sc.err(at, "expected a type after DEF", "DEF"));
        };
        if matches!(ty, "STRING" | "CHAR" | "AXIS" | "FRAME") {
            let text = String::from_utf8_lossy(&sc.s[t_at..]);
            let text = text.split(';').next().unwrap_or("").trim().to_string();
            sc.at = sc.s.len();
            self.notice(
                line_no,
                format!("`DEF {text}`: a {ty} variable (Sinumerik programming manual, \"Variable types\") is accepted and not held: a use of it in a move or a condition is refused"),
            );
            return Ok(());
        }
        if !matches!(ty, "REAL" | "INT" | "BOOL") {
            return Err(sc.err(
                t_at,
                format!("`DEF {ty}`: mtsim reads REAL, INT and BOOL variables (STRING, CHAR, AXIS and FRAME with a notice)"),
                "unsupported type",
            ));
        }
        let integer = ty != "REAL";
        loop {
            let Some((name, n_at)) = sc.ident() else {
                return Err(sc.err(sc.at, "expected a variable name", "no name"));
            };
            let dims = if sc.peek() == Some(b'[') {
                indices(sc, &self.vars, n_at)?
            } else {
                Vec::new()
            };
            let reserved = (name.len() == 1 && name.as_bytes()[0].is_ascii_uppercase())
                || r_parameter(name).is_some()
                || NOTED.contains(&name);
            if reserved {
                return Err(sc.err(n_at, format!("`{name}` is an address or keyword: expected a variable name of two or more characters that is not one"), "reserved name"));
            }
            let name = name.to_string();
            let values = self.def_values(sc, n_at, &name, &dims, integer)?;
            let level = self.vars.levels.last_mut().expect("a variable level");
            if level.len() + values.len() > MAX_VARIABLES {
                return Err(sc.err(
                    n_at,
                    format!("more than {MAX_VARIABLES} variables (array elements counted) in one program"),
                    "too many variables",
                ));
            }
            level.extend(values);
            if !sc.eat(b',') {
                return Ok(());
            }
        }
    }

    /// A `DEF`'s variable and its starting value, or an array's elements (Sinumerik
    /// programming manual, "Definition and initialization of array variables"): `=v`,
    /// `=(v0, v1 …)` or `=SET(v0, v1 …)` in row-major order with the rest 0, `=REP(v)`
    /// for every element; elements start at 0.
    fn def_values(
        &mut self,
        sc: &mut Scan,
        at: usize,
        name: &str,
        dims: &[usize],
        integer: bool,
    ) -> LineResult<Vec<(String, f64)>> {
        let count = dims.iter().try_fold(1usize, |n, d| n.checked_mul(*d));
        let count = match count {
            Some(n) if n <= MAX_VARIABLES => n,
            _ => {
                return Err(sc.err(
                    at,
                    format!("array `{name}` of more than {MAX_VARIABLES} elements"),
                    "array too large",
                ))
            }
        };
        let whole = |v: f64| if integer { v.round() } else { v };
        let mut first = Vec::new();
        let mut repeat = false;
        if sc.eat(b'=') {
            let list = if dims.is_empty() {
                false
            } else if sc.keyword("REP") {
                repeat = true;
                true
            } else {
                sc.keyword("SET");
                sc.peek() == Some(b'(')
            };
            if list {
                sc.eat(b'(');
                loop {
                    first.push(whole(expr(sc, &self.vars)?));
                    if sc.eat(b')') {
                        break;
                    }
                    if !sc.eat(b',') {
                        return Err(sc.err(
                            at,
                            format!("expected `,` or `)` in the values of `{name}`"),
                            "unclosed list",
                        ));
                    }
                }
            } else {
                first.push(whole(expr(sc, &self.vars)?));
                repeat = !dims.is_empty();
            }
        }
        if dims.is_empty() {
            return Ok(vec![(
                name.to_string(),
                first.first().copied().unwrap_or(0.0),
            )]);
        }
        if first.len() > count {
            return Err(sc.err(
                at,
                format!(
                    "{} values for the {count} elements of `{name}`",
                    first.len()
                ),
                "too many values",
            ));
        }
        let mut out = Vec::with_capacity(count);
        let mut index = vec![0usize; dims.len()];
        for k in 0..count {
            let v = match (repeat, first.get(k)) {
                (true, _) => first.first().copied().unwrap_or(0.0),
                (false, Some(v)) => *v,
                (false, None) => 0.0,
            };
            out.push((element_key(name, &index), v));
            // Row-major: the last index runs fastest.
            for d in (0..dims.len()).rev() {
                index[d] += 1;
                if index[d] < dims[d] {
                    break;
                }
                index[d] = 0;
            }
        }
        Ok(out)
    }

    /// `PROC name(REAL a, INT b ...)`: the call's values bound to the parameters.
    fn proc(&mut self, sc: &mut Scan, at: usize) -> LineResult<()> {
        sc.ident();
        let args = std::mem::take(&mut self.level().args);
        if !sc.eat(b'(') {
            return Ok(());
        }
        let mut k = 0;
        while !sc.eat(b')') {
            let Some((ty, _)) = sc.ident() else {
                return Err(sc.err(at, "expected `type name` in the PROC parameters", "PROC"));
            };
            let by_reference = ty == "VAR";
            let ty = if by_reference {
                sc.ident().map_or("", |t| t.0)
            } else {
                ty
            };
            let Some((name, n_at)) = sc.ident() else {
                return Err(sc.err(at, "expected a parameter name", "PROC"));
            };
            if !matches!(ty, "REAL" | "INT" | "BOOL") || by_reference {
                return Err(sc.err(n_at, format!("PROC parameter `{name}` of type {ty}{}: mtsim reads REAL, INT and BOOL values", if by_reference { " by reference (VAR)" } else { "" }), "unsupported parameter"));
            }
            let v = args.get(k).copied().unwrap_or(0.0);
            self.vars
                .levels
                .last_mut()
                .expect("a variable level")
                .insert(name.to_string(), v);
            k += 1;
            sc.eat(b',');
            if sc.done() {
                break;
            }
        }
        Ok(())
    }

    /// `TRANS X.. Y.. Z..`, `ROT X.. Y.. Z..` / `ROT RPL=..`, `SCALE`, `MIRROR` and their
    /// additive forms; with no axes, the absolute form clears the programmable frame.
    fn frame_statement(&mut self, kw: &str, sc: &mut Scan, at: usize) -> LineResult<()> {
        let additive = kw.starts_with('A');
        // ATRANS → TRANS, AROT → ROT, ASCALE → SCALE, AMIRROR → MIRROR.
        let base = if additive { &kw[1..] } else { kw };
        let mut v: [Option<f64>; 3] = [None; 3];
        let mut rpl = None;
        while !sc.done() {
            let Some((name, n_at)) = sc.ident() else {
                return Err(sc.err(sc.at, format!("expected axis values after {kw}"), "frame"));
            };
            let slot = match name {
                "X" => 0,
                "Y" => 1,
                "Z" => 2,
                "RPL" => 3,
                _ => {
                    let (letter, digits) = name.split_at(1);
                    let k = "XYZ"
                        .find(letter)
                        .filter(|_| digits.bytes().all(|b| b.is_ascii_digit() || b == b'.'));
                    let Some(k) = k else {
                        return Err(sc.err(
                            n_at,
                            format!("`{name}` in {kw}: expected X, Y, Z (or RPL= for ROT)"),
                            "frame axis",
                        ));
                    };
                    sc.at = n_at + 1;
                    k
                }
            };
            sc.eat(b'=');
            let value = expr(sc, &self.vars)?;
            if slot == 3 {
                rpl = Some(value);
            } else {
                v[slot] = Some(value);
            }
        }
        let instruction = match base {
            "TRANS" => Instruction::Trans(v.map(|x| x.unwrap_or(0.0))),
            "ROT" => {
                let mut angles = v.map(|x| x.unwrap_or(0.0));
                if let Some(a) = rpl {
                    angles = [0.0; 3];
                    angles[self.normal] = a;
                }
                Instruction::Rot(rotation_zyx(angles[0], angles[1], angles[2]))
            }
            "SCALE" => {
                let s = v.map(|x| x.unwrap_or(1.0));
                if s.iter().any(|x| *x == 0.0 || !x.is_finite()) {
                    return Err(sc.err(
                        at,
                        "a scale of zero: expected non-zero factors",
                        "zero scale",
                    ));
                }
                Instruction::Scale(s)
            }
            _ => Instruction::Mirror(v.map(|x| x.is_some())),
        };
        self.programmable(instruction, additive);
        Ok(())
    }

    /// The identifier `name` inside a list of words: a keyword, an assignment, `CR=`, a
    /// message, a cycle or a subprogram call.
    pub(super) fn named(
        &mut self,
        name: &str,
        at: usize,
        sc: &mut Scan,
        w: &mut Words,
        line_no: usize,
    ) -> LineResult<()> {
        match name {
            "R" if sc.peek() == Some(b'[') => {
                sc.eat(b'[');
                let k = expr(sc, &self.vars)?;
                if !sc.eat(b']')
                    || !(0.0..self.vars.r.len() as f64).contains(&k)
                    || k.fract() != 0.0
                {
                    return Err(sc.err(
                        at,
                        "expected `R[index]` with an index 0-999",
                        "R parameter",
                    ));
                }
                return self.assign(sc, Var::R(k as usize), at);
            }
            "CR" => {
                if !sc.eat(b'=') {
                    return Err(sc.err(at, "expected `CR=radius`", "CR"));
                }
                w.cr = Some((expr(sc, &self.vars)?, at..sc.at));
                return Ok(());
            }
            "HOLES1" | "HOLES2" => return self.hole_pattern(name, at, sc, line_no),
            n if super::patterns::UNREAD_CYCLES.iter().any(|(k, _)| *k == n) => {
                return Err(super::patterns::unread_cycle(n, sc, at))
            }
            "AR" | "ANG" => return self.angle_word(name, at, sc, w),
            "CHF" | "CHR" | "RND" | "RNDM" => return self.corner_word(name, at, sc, w),
            "ADIS" | "ADISPOS" if sc.peek() == Some(b'=') => {
                // The rounding distance of G641/G642 path blending: the planner does not
                // blend by it (docs/interpolation.md).
                sc.eat(b'=');
                expr(sc, &self.vars)?;
                self.notice(
                    line_no,
                    format!("`{name}=` (the rounding distance of G641/G642 blending) accepted and not simulated"),
                );
                return Ok(());
            }
            "MSG" => return skip_call(sc, at),
            "A3" | "B3" | "C3" => return self.orientation_word(name, at, sc, w),
            _ if self.machine_word(name, at, sc, w, line_no)? => return Ok(()),
            _ if self.fixed_point_word(name, at, sc, w)? => return Ok(()),
            "CT" | "CIP" | "TURN" | "AP" | "RP" | "I1" | "J1" | "K1" => {
                return self.geometry_word(name, at, sc, w)
            }
            n if REFUSED.iter().any(|(k, _, _)| *k == n) => {
                let (what, section) = REFUSED
                    .iter()
                    .find(|(k, _, _)| *k == n)
                    .map_or(("", ""), |(_, w, s)| (*w, *s));
                return Err(sc.err(at, format!("`{n}` ({what}) is not supported by mtsim's Siemens reader (SINUMERIK 840D sl programming manual {section}; docs/gcode.md lists what it reads)"), "unsupported Sinumerik word"));
            }
            n if NOTED.contains(&n) => {
                if sc.peek() == Some(b'(') {
                    skip_call(sc, at)?;
                }
                self.notice(line_no, format!("`{n}` accepted and not simulated"));
                return Ok(());
            }
            _ => {}
        }
        if name == "$P_UIFR" && sc.peek() == Some(b'[') {
            return self.settable_write(sc, at);
        }
        if name == "$P_PFRAME" {
            return self.programmable_write(sc, at);
        }
        if name.starts_with('$') {
            return Err(sc.err(
                at,
                format!(
                    "system variable `{name}` ({}) is not supported by mtsim: its value is the control's, and neither the machine file nor the scenario gives it",
                    system_variable_kind(name)
                ),
                "system variable",
            ));
        }
        match sc.peek() {
            Some(b'=') if self.vars.get(name).is_some() => {
                return self.assign(sc, Var::Named(name.to_string()), at);
            }
            Some(b'=') => return Err(undefined(sc, at, name)),
            Some(b'[') => {
                let key = element(sc, &self.vars, name, at)?;
                return self.assign(sc, Var::Named(key), at);
            }
            _ => {}
        }
        if name.starts_with("CYCLE") {
            return self.cycle_word(name, at, sc, line_no);
        }
        // A subprogram called by name, with values in parentheses.
        let mut args = Vec::new();
        if sc.eat(b'(') {
            while !sc.eat(b')') {
                if sc.peek() == Some(b',') {
                    args.push(0.0);
                } else {
                    args.push(expr(sc, &self.vars)?);
                }
                if !sc.eat(b',') && sc.peek() != Some(b')') {
                    return Err(sc.err(
                        at,
                        format!("expected `,` or `)` in the call of `{name}`"),
                        "call",
                    ));
                }
                if args.len() > 64 {
                    return Err(sc.err(at, "more than 64 values in a call", "call"));
                }
            }
        }
        w.call = Some((name.to_string(), args, at..sc.at));
        Ok(())
    }

    /// `MCALL CYCLE8x(..)` sets the modal call, `MCALL` alone clears it.
    fn mcall(&mut self, sc: &mut Scan, at: usize, _line_no: usize) -> LineResult<()> {
        if sc.done() {
            self.modal_call = None;
            return Ok(());
        }
        let Some((name, n_at)) = sc.ident() else {
            return Err(sc.err(at, "expected a cycle after MCALL", "MCALL"));
        };
        self.modal_call = Some(self.cycle(name, n_at, sc)?);
        Ok(())
    }
}

/// Skips `( ... )` with strings inside, after a name.
pub(super) fn skip_call(sc: &mut Scan, at: usize) -> LineResult<()> {
    if !sc.eat(b'(') {
        return Ok(());
    }
    let mut depth = 1;
    let mut quoted = false;
    while let Some(&c) = sc.s.get(sc.at) {
        sc.at += 1;
        match c {
            b'"' => quoted = !quoted,
            b'(' if !quoted => depth += 1,
            b')' if !quoted => {
                depth -= 1;
                if depth == 0 {
                    return Ok(());
                }
            }
            _ => {}
        }
    }
    Err(sc.err(at, "expected `)` to close this call", "unclosed call"))
}
