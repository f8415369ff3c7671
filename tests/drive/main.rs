//! The drive stage (`src/drive/`): the servo models against the closed forms of
//! `docs/servo.md`, the cascade's exact period map, and pre-sliding friction.

mod lanes;
mod presliding;
mod servo_closed_form;
mod servo_exact_map;
