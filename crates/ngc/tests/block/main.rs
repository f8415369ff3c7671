//! Words into typed blocks: what a block of the G-code dialects accepts and computes (arcs,
//! units, modal state carried over), where its errors are reported, the short path of plain
//! `G0`/`G1` blocks, and the code tables docs/gcode.md lists.

mod gcode_doc;
mod plain_moves;
mod reader;
