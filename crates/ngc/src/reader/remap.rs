//! LinuxCNC remapped codes (`[RS274NGC]REMAP`, crate `remap`): a block with a remapped
//! code runs the words before it, the code's o-word subroutine (with LinuxCNC's stdglue
//! prolog and epilog emulated, crate `stdglue`), and on return the words after it.

use crate::lex::{LineError, LineResult, Word};
use crate::notice::Notice;

use super::state::{Cursor, Epilog, IsoReader, Resume};

impl IsoReader {
    /// Runs a block with a remapped code: the words before it, the handler, and (on return,
    /// or at once for an accepted Python handler) the words after it.
    pub(super) fn run_remap(
        &mut self,
        line: &str,
        words: &[Word],
        s: crate::remap::Split,
        here: Cursor,
        next: Cursor,
    ) -> LineResult<()> {
        let remap = self.remaps[s.remap].clone();
        let name = if s.explicit {
            line[s.span.clone()].to_string()
        } else {
            format!(
                "{} (the modal cycle, called again by axis words)",
                remap.code
            )
        };
        // Python prolog/epilog handlers: LinuxCNC's stdglue ones are emulated
        // (crate::stdglue); others cannot be run.
        let unknown = [&remap.prolog, &remap.epilog]
            .into_iter()
            .flatten()
            .find(|name| crate::stdglue::Handler::named(name).is_none())
            .map(|name| format!("the Python handler `{name}` is not one of LinuxCNC's stdglue.py handlers mtsim emulates ({})", crate::stdglue::NAMES));
        if let Some(why) = unknown.as_ref().or(remap.handlers_refused.as_ref()) {
            return Err(LineError::new(s.span.clone(), format!("`{name}` is remapped ({}) with Python prolog/epilog handlers around its subroutine: {why}; mtsim runs no Python, and such handlers set the parameters the subroutine reads", remap.origin), "Python remap")
                .help("remap the code with LinuxCNC's stdglue handlers or without prolog= and epilog=, or remove it from the program"));
        }
        let glue = |h: &Option<String>| h.as_deref().and_then(crate::stdglue::Handler::named);
        let (prolog, epilog) = (glue(&remap.prolog), glue(&remap.epilog));
        let pick = |idx: &[usize]| idx.iter().map(|&k| words[k]).collect::<Vec<_>>();
        let before = pick(&s.before);
        if !before.is_empty() {
            self.run_block(line, &before, here, next)?;
        }
        let after = pick(&s.after);
        let Some(label) = &remap.ngc else {
            if let Some(why) = &remap.python_motion {
                return Err(LineError::new(s.span.clone(), format!("`{name}` is remapped ({}) to the Python function `{}`: {why}; mtsim runs no Python", remap.origin, remap.python.as_deref().unwrap_or("")), "Python remap")
                    .help("remap it to an o-word subroutine (ngc=), or remove it from the program"));
            }
            if !self.remaps_noticed.contains(&s.remap) {
                self.remaps_noticed.push(s.remap);
                self.notices.push(Notice { path: self.programs[here.file].path.clone(), line: here.line, message: format!("{} is remapped ({}) to the Python function `{}`, which does not move the machine: accepted and not run", remap.code, remap.origin, remap.python.as_deref().unwrap_or("")), warning: false });
            }
            if remap.python_keeps_motion {
                self.modal_remap = Some(s.remap);
            }
            return if after.is_empty() {
                Ok(())
            } else {
                self.run_block(line, &after, here, next)
            };
        };
        let positional: Vec<f64> = if remap.positional() {
            remap
                .letters()
                .map(|(l, _)| s.args.iter().find(|a| a.0 == l).map_or(0.0, |a| a.1))
                .collect()
        } else {
            Vec::new()
        };
        let set = match prolog {
            None => Vec::new(),
            Some(h) => {
                let change = if h == crate::stdglue::Handler::ChangeProlog {
                    self.interp.tool_change_parameters()
                } else {
                    None
                };
                let interp = &self.interp;
                let call = crate::stdglue::Call {
                    code: remap.code,
                    value: s.value,
                    q: s.q,
                    words: &s.args,
                    explicit: s.explicit,
                    cycle_typeerror: remap.cycle_prolog_typeerror,
                };
                crate::stdglue::prolog(
                    h,
                    &call,
                    s.remap,
                    interp.glue_view(),
                    &mut self.sticky,
                    &|n| interp.glue_pocket(n),
                    &|n| interp.params.numbered.get(n).copied().unwrap_or(0.0),
                    change,
                )
                .map_err(|m| {
                    LineError::new(
                        s.span.clone(),
                        format!("`{name}`: {m} (stdglue {}, {})", h.name(), remap.origin),
                        "remap prolog",
                    )
                })?
            }
        };
        self.call(label, &positional, true, 1, here, next, s.span.clone())?;
        if !remap.positional() {
            if let Some(locals) = self.interp.params.locals.last_mut() {
                for (letter, v) in &s.args {
                    locals.insert(letter.to_ascii_lowercase().to_string(), *v);
                }
            }
        }
        if let Some(locals) = self.interp.params.locals.last_mut() {
            for (k, v) in set {
                locals.insert(k, v);
            }
        }
        let base = line.as_ptr() as usize;
        let frame = self.frames.last_mut().expect("just called");
        frame.remap = Some(s.remap);
        frame.epilog = epilog.map(|handler| {
            Box::new(Epilog {
                handler,
                remap: s.remap,
                builtin_used: false,
                here,
                span: s.span.clone(),
            })
        });
        if !after.is_empty() {
            frame.resume = Some(Resume {
                here,
                line: line.to_string(),
                words: after
                    .iter()
                    .map(|w| {
                        let at = if w.number.is_empty() {
                            0
                        } else {
                            w.number.as_ptr() as usize - base
                        };
                        (w.letter, w.value, at..at + w.number.len(), w.span)
                    })
                    .collect(),
            });
        }
        Ok(())
    }
}
