//! Program text into words: numbers read exactly, expressions nested to their bound, and
//! files beside the program (subroutine files streamed, side files bounded).

mod nesting;
mod numbers;
mod side_files;
