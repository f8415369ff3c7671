//! Phase 2: T selects a tool, M6 (Haas: also M16) changes to it, M61 sets it; user M codes (mapped in the
//! scenario, or M100-M199 programs); the spindle turns after the change (M3/M4) or stops
//! (M5), as LinuxCNC's order of execution has it.

use std::path::Path;

use super::Interp;
use crate::block::Block;
use crate::lex::{LineError, LineResult, Word};
use crate::notice::Notice;
use crate::options::{Tool, UserM};

impl Interp {
    /// Phase 2: T, M6/M61, user M codes, then M3/M4/M5.
    pub(super) fn tool_and_spindle(
        &mut self,
        b: &Block,
        line_no: usize,
        notices: &mut Vec<Notice>,
        path: &Path,
    ) -> LineResult<()> {
        if let Some(t) = b.get('T') {
            let n = t.value.round() as u32;
            if self.is_lathe() {
                // A Fanuc or Haas lathe's T: the turret indexes to the tool of the leading
                // digits at once, the last two select its offset (T0101, parameter 5028 at 2).
                if (1..100).contains(&n) {
                    return Err(LineError::new(t.span(), format!("`{}` on a {} lathe: T is the tool and its offset number, two digits each (T0101: tool 1, offset 1); expected four digits", &b.line[t.span()], self.dialect.name()), "lathe T word"));
                }
                let tool = n / 100;
                self.tool_entry(tool, &t)?;
                self.next_tool = tool;
                self.tool = tool;
                return self.spindle_and_m(b, line_no, notices, path);
            }
            self.tool_entry(n, &t)?;
            self.next_tool = n;
            self.tool_selected = true;
        }
        self.spindle_and_m(b, line_no, notices, path)
    }

    /// The block's M codes: tool change, user M codes, spindle, the control's own codes.
    fn spindle_and_m(
        &mut self,
        b: &Block,
        line_no: usize,
        notices: &mut Vec<Notice>,
        path: &Path,
    ) -> LineResult<()> {
        let mut tcp_m = None;
        let machine_m = self.dialect.table().machine_m;
        let m16_tool_change = self.dialect.table().m16_tool_change;
        for &(code, w) in b.m.iter() {
            // Haas M16 is M06 under another number (HM M16).
            let code = if code == 16 && m16_tool_change {
                6
            } else {
                code
            };
            match code {
                // The control's own machine codes first (Haas M61-M68 are relays, not
                // LinuxCNC's M61 Q tool number or M62-M68 I/O).
                code if machine_m(code).is_some() => {}
                6 if self.comp.is_some() => {
                    return Err(LineError::new(w.span(), "cannot change tools with cutter radius compensation on: expected G40 first", "tool change under compensation"));
                }
                6 => {
                    self.tool = self.next_tool;
                    // rs274's default: the spindle stops for a tool change.
                    self.spindle_turning = false;
                    // LinuxCNC resynchronises after a tool change: the program point
                    // becomes where the tool is (the compensated point after G40).
                    if let Some(p) = self.comp_out.take() {
                        self.pos = p;
                    }
                }
                61 => {
                    let Some(q) = b.get('Q') else {
                        return Err(LineError::new(
                            w.span(),
                            "M61 without Q: expected `M61 Q<tool>`",
                            "no Q",
                        ));
                    };
                    let n = q.value.round() as u32;
                    self.tool_entry(n, &q)?;
                    self.tool = n;
                    self.next_tool = n;
                }
                0 | 1 | 2 | 30 | 60 | 3 | 4 | 5 | 19 | 7 | 8 | 9 | 48..=53 | 62..=68 | 98 | 99 => {}
                70..=73 if self.dialect.table().modal_state_m70_m73 => {}
                97 if self.dialect.table().local_subprogram_m97 => {}
                code => {
                    if let Some(on) = self.user_m(b.line, code, w, line_no, notices, path)? {
                        tcp_m = Some(on);
                    }
                }
            }
        }
        match tcp_m {
            Some(true) => self.tcp = true,
            Some(false) => self.tcp_cancel(),
            None => {}
        }
        // After M6 (LinuxCNC's order of execution): M3/M4 start the spindle, M5 stops it.
        for &(code, _) in b.m.iter() {
            match code {
                3 | 4 => self.spindle_turning = true,
                5 => self.spindle_turning = false,
                _ => {}
            }
        }
        Ok(())
    }

    /// A user M code: mapped in the scenario (TCP on, off, ignored), or an M100-M199
    /// program, accepted with a notice. `Some(on)` when it switches TCP.
    pub(super) fn user_m(
        &mut self,
        line: &str,
        code: u32,
        w: Word,
        line_no: usize,
        notices: &mut Vec<Notice>,
        path: &Path,
    ) -> LineResult<Option<bool>> {
        match self.user_m.get(&code) {
            Some(UserM::TcpOn) => Ok(Some(true)),
            Some(UserM::TcpOff) => Ok(Some(false)),
            Some(UserM::Ignore) => Ok(None),
            None if (100..=199).contains(&code) => {
                let file = self
                    .user_m_path
                    .iter()
                    .map(|d| d.join(format!("M{code}")))
                    .find(|p| p.is_file());
                if file.is_none() && !self.user_m_path.is_empty() {
                    return Err(LineError::new(w.span(), format!("user code `{}` has no program `M{code}` on the configuration's USER_M_PATH or PROGRAM_PREFIX: LinuxCNC refuses it (unknown M code)", &line[w.span()]), "no user M program")
                        .help("add the M program to the configuration, or map the code in the scenario's user_m_codes"));
                }
                if !self.noticed.contains(&code) && self.noticed.len() < 100 {
                    self.noticed.push(code);
                    let what = file.map_or(String::new(), |f| {
                        format!(" (runs {}, an external program)", f.display())
                    });
                    notices.push(Notice { path: path.to_path_buf(), line: line_no, message: format!("user code M{code}{what} accepted and ignored (map it in the scenario's user_m_codes to give it an effect)"), warning: false });
                }
                Ok(None)
            }
            None => {
                Err(LineError::new(w.span(), format!("unsupported code `{}`", &line[w.span()]), "unsupported M code")
                    .help("supported: M0-M9 M19 M30 M48-M53 M60-M68 M98 M99, M70-M73 in the linuxcnc dialect, the machine codes docs/gcode.md lists for fanuc and haas, and user M100-M199; map others in the scenario's user_m_codes"))
            }
        }
    }

    pub(super) fn tool_entry(&self, n: u32, w: &Word) -> LineResult<Tool> {
        match self.tools.get(&n) {
            Some(t) => Ok(*t),
            None if !self.table_given || n == 0 => Ok(Tool {
                number: n,
                length_mm: 0.0,
                diameter_mm: 0.0,
            }),
            None => Err(LineError::new(
                w.span(),
                format!("tool {n} is not in the tool table: expected one of its tools"),
                "unknown tool",
            )
            .help("add the tool to the scenario's tool table")),
        }
    }
}
