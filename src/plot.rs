//! Polar plot.
