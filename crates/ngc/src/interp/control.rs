//! The control's parameters a block depends on ([`ControlParameters`]): a notice, once
//! per setting, where the machine file does not give a setting the control takes the
//! block's motion from, naming the setting and the value the reader used instead.
//!
//! [`ControlParameters`]: crate::options::ControlParameters

use std::path::Path;

use super::Interp;
use crate::block::Block;
use crate::code::{GCode, MotionMode, NonModal};
use crate::notice::Notice;
use crate::options::PECK_CLEARANCE_MM;

/// Keys of these notices in `noticed`, apart from the G and M codes' (below 1 << 21).
const PECK_KEY: u32 = 1 << 22;
const REFERENCE_KEY: u32 = (1 << 22) + 1;

impl Interp {
    /// The notices of the block's dependence on settings not given: a G73 or G83 cycle
    /// whose retract or clearance is a setting of the control, and a G28/G30 without
    /// axis words on a control where it moves nothing.
    pub(super) fn control_notices(
        &mut self,
        b: &Block,
        line_no: usize,
        notices: &mut Vec<Notice>,
        path: &Path,
    ) {
        let table = self.dialect.table();
        let mut say = |interp: &mut Interp, key: u32, message: String| {
            if !interp.noticed.contains(&key) {
                interp.noticed.push(key);
                notices.push(Notice {
                    path: path.to_path_buf(),
                    line: line_no,
                    message,
                    warning: false,
                });
            }
        };
        for (code, _) in b.g.iter() {
            match code {
                GCode::Motion(Some(MotionMode::Cycle(c @ (730 | 830)))) => {
                    let (given, setting, key) = if *c == 730 {
                        (
                            self.control.g73_retract_mm,
                            table.peck_settings.map(|s| s.0),
                            "g73_retract_mm",
                        )
                    } else {
                        (
                            self.control.g83_clearance_mm,
                            table.peck_settings.map(|s| s.1),
                            "g83_clearance_mm",
                        )
                    };
                    if let (None, Some(setting)) = (given, setting) {
                        let what = if *c == 730 {
                            "retract after each peck"
                        } else {
                            "re-approach clearance above each peck"
                        };
                        say(self, PECK_KEY + c, format!(
                            "G{} {what}: {setting} of the {} control, not given by the machine file: \
                             {PECK_CLEARANCE_MM} mm used (set `[control] {key}`)",
                            c / 10,
                            self.dialect.name()
                        ));
                    }
                }
                GCode::NonModal(nm @ (NonModal::G28 | NonModal::G30))
                    if b.axis.is_empty() && !self.reference_all_without_axes() =>
                {
                    let name = if *nm == NonModal::G28 { "G28" } else { "G30" };
                    say(
                        self,
                        REFERENCE_KEY,
                        format!(
                        "{name} without axis words moves no axis on a {} control (only the axes \
                         named return); set `[control] g28_without_axes = \"all\"` if this \
                         machine returns them all",
                        self.dialect.name()
                    ),
                    );
                }
                _ => {}
            }
        }
    }
}
