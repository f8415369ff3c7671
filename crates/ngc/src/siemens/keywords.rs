//! The Sinumerik keywords the front end accepts with a notice (they do not change the
//! path mtsim reads) and those it refuses by name, with what each is and the SINUMERIK
//! 840D sl programming manual section that describes it.

/// Keywords accepted anywhere in a block that do not change the path mtsim reads
/// (dynamics, compressors, look-ahead, orientation reference): noted once.
pub(super) const NOTED: &[&str] = &[
    "SOFT",
    "BRISK",
    "FFWON",
    "FFWOF",
    "COMPOF",
    "COMPON",
    "COMPCAD",
    "COMPCURV",
    "CFC",
    "CFTCP",
    "CFIN",
    "STOPRE",
    // The blank's shape and size for the control's simulation display.
    "WORKPIECE",
    "SPATH",
    "UPATH",
    "ORIAXES",
    "ORIVECT",
    "SETMS",
    "DIAMOF",
    "ACN",
    "ACP",
    "DC",
    "G64",
    "WAITM",
    "PTP",
    "CP",
    "DRIVE",
    "FGROUP",
    "GROUP_BEGIN",
    "GROUP_END",
    "DISPLOF",
    "DISPLON",
    "SAVE",
    "FIFOCTRL",
];

/// Sinumerik words mtsim knows and does not read: refused with what they are and the
/// SINUMERIK 840D sl programming manual section that describes them.
pub(super) const REFUSED: &[(&str, &str, &str)] = &[
    (
        "FRC",
        "feed of a chamfer or rounding",
        "Fundamentals, \"Chamfer, rounding (CHF, CHR, RND, RNDM, FRC, FRCM)\"",
    ),
    (
        "FRCM",
        "modal feed of chamfers and roundings",
        "Fundamentals, \"Chamfer, rounding (CHF, CHR, RND, RNDM, FRC, FRCM)\"",
    ),
    (
        "OFFN",
        "contour offset",
        "Fundamentals, \"Tool radius compensation (G40, G41, G42, OFFN)\"",
    ),
    (
        "SPOSA",
        "spindle positioning",
        "Fundamentals, \"Spindle positioning (SPOS, SPOSA, M19)\"",
    ),
    (
        "POLY",
        "polynomial interpolation",
        "Job planning, \"Polynomial interpolation (POLY)\"",
    ),
    (
        "ASPLINE",
        "spline",
        "Job planning, \"Spline interpolation (ASPLINE, BSPLINE, CSPLINE)\"",
    ),
    (
        "BSPLINE",
        "spline",
        "Job planning, \"Spline interpolation (ASPLINE, BSPLINE, CSPLINE)\"",
    ),
    (
        "CSPLINE",
        "spline",
        "Job planning, \"Spline interpolation (ASPLINE, BSPLINE, CSPLINE)\"",
    ),
    (
        "TRANSMIT",
        "face transformation",
        "Job planning, \"Kinematic transformations (TRANSMIT)\"",
    ),
    (
        "TRACYL",
        "cylinder transformation",
        "Job planning, \"Kinematic transformations (TRACYL)\"",
    ),
    (
        "TRAANG",
        "inclined-axis transformation",
        "Job planning, \"Kinematic transformations (TRAANG)\"",
    ),
    (
        "TOFRAME",
        "tool frame",
        "Job planning, \"Frames: tool frame (TOFRAME)\"",
    ),
    (
        "TCARR",
        "tool carrier",
        "Job planning, \"Tool carrier (TCARR, TCOABS, TCOFR)\"",
    ),
    (
        "PAROT",
        "workpiece-aligned frame",
        "Job planning, \"Frames: workpiece-aligned frame (PAROT)\"",
    ),
    (
        "A2",
        "orientation angle",
        "Job planning, \"Orientation programming: Euler or RPY angles (A2, B2, C2)\"",
    ),
    (
        "B2",
        "orientation angle",
        "Job planning, \"Orientation programming: Euler or RPY angles (A2, B2, C2)\"",
    ),
    (
        "C2",
        "orientation angle",
        "Job planning, \"Orientation programming: Euler or RPY angles (A2, B2, C2)\"",
    ),
];
