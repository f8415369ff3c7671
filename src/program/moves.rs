//! The stream of canonical moves that every program source yields, and its tee: one reading
//! for two readers that go at their own pace.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;

use crate::error::Result;
use ngc::Move;

/// A stream of canonical moves; yields at most one error, then stops.
pub type Moves<'a> = Box<dyn Iterator<Item = Result<Move>> + 'a>;

/// `moves` read once for two readers: each of the two streams yields every move of `moves`
/// in order, whichever of them reads further ahead. A move read by one is kept, as a copy,
/// until the other has read it too, so what is held is the distance between the two readers
/// (for the run and its contour gauge: the planner's look-ahead), not the program.
///
/// An error ends the source: the reader that meets it gets it, and the other ends with the
/// moves before it. Both readers of a run stop the run on an error, so the run fails with
/// the error whichever reader met it first.
pub fn tee(moves: Moves<'_>) -> (Moves<'_>, Moves<'_>) {
    let (first, second) = tee_readers(moves);
    (Box::new(first), Box::new(second))
}

fn tee_readers(moves: Moves<'_>) -> (TeeReader<'_>, TeeReader<'_>) {
    let shared = Rc::new(RefCell::new(TeeSource {
        source: moves,
        kept: VecDeque::new(),
        ahead: Side::First,
        ended: false,
        alone: false,
    }));
    let first = TeeReader {
        shared: Rc::clone(&shared),
        side: Side::First,
    };
    let second = TeeReader {
        shared,
        side: Side::Second,
    };
    (first, second)
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Side {
    First,
    Second,
}

struct TeeSource<'a> {
    source: Moves<'a>,
    /// Moves the reader `ahead` has read and the other has not, oldest first.
    kept: VecDeque<Move>,
    ahead: Side,
    /// The source has ended or failed: nothing more is read from it.
    ended: bool,
    /// One reader is gone: the other keeps nothing for it.
    alone: bool,
}

struct TeeReader<'a> {
    shared: Rc<RefCell<TeeSource<'a>>>,
    side: Side,
}

impl Iterator for TeeReader<'_> {
    type Item = Result<Move>;

    fn next(&mut self) -> Option<Result<Move>> {
        let mut s = self.shared.borrow_mut();
        if s.ahead != self.side {
            if let Some(m) = s.kept.pop_front() {
                return Some(Ok(m));
            }
            // Caught up: this reader now reads the source first.
            s.ahead = self.side;
        }
        if s.ended {
            return None;
        }
        match s.source.next() {
            Some(Ok(m)) => {
                if !s.alone {
                    s.kept.push_back(m.clone());
                }
                Some(Ok(m))
            }
            Some(Err(e)) => {
                s.ended = true;
                Some(Err(e))
            }
            None => {
                s.ended = true;
                None
            }
        }
    }
}

impl Drop for TeeReader<'_> {
    fn drop(&mut self) {
        let mut s = self.shared.borrow_mut();
        s.alone = true;
        // What is kept was kept for the reader behind: forget it if that is this one; the
        // reader left behind still takes it.
        if s.ahead != self.side {
            s.kept.clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A program of `n` moves (lines 1..=n) that fails at line `fail_at`, then stops.
    fn program(n: usize, fail_at: Option<usize>) -> Moves<'static> {
        let last = fail_at.unwrap_or(n).min(n);
        Box::new((1..=last).map(move |line| {
            if Some(line) == fail_at {
                Err(crate::error::Error::usage(format!("line {line}")))
            } else {
                Ok(Move {
                    line,
                    ..Move::default()
                })
            }
        }))
    }

    fn lines(moves: &mut dyn Iterator<Item = Result<Move>>, n: usize) -> Vec<usize> {
        moves.take(n).map(|m| m.unwrap().line).collect()
    }

    /// Two readers at any pace each read every move once, in order.
    #[test]
    fn both_readers_get_every_move_in_order_at_any_pace() {
        for lead in [0usize, 1, 3, 10, 50] {
            let (mut a, mut b) = tee(program(40, None));
            let mut got_a = lines(&mut a, lead);
            let mut got_b = Vec::new();
            loop {
                let (x, y) = (a.next(), b.next());
                if x.is_none() && y.is_none() {
                    break;
                }
                got_a.extend(x.map(|m| m.unwrap().line));
                got_b.extend(y.map(|m| m.unwrap().line));
                // The second reader now and then takes two, and overtakes.
                if got_b.len() % 7 == 0 {
                    got_b.extend(b.next().map(|m| m.unwrap().line));
                }
            }
            let want: Vec<usize> = (1..=40).collect();
            assert_eq!(got_a, want, "lead {lead}");
            assert_eq!(got_b, want, "lead {lead}");
        }
    }

    /// What is kept is the distance between the readers, not the program.
    #[test]
    fn it_keeps_only_what_one_reader_is_ahead() {
        let (mut a, mut b) = tee_readers(program(1000, None));
        assert_eq!(lines(&mut a, 3), vec![1, 2, 3]);
        for k in 1..=997 {
            assert_eq!(b.next().unwrap().unwrap().line, k);
            assert_eq!(a.next().unwrap().unwrap().line, k + 3);
            assert_eq!(a.shared.borrow().kept.len(), 3);
        }
        assert_eq!(lines(&mut b, 10), vec![998, 999, 1000]);
        assert!(a.shared.borrow().kept.is_empty());
    }

    /// The reader that meets the error gets it; the other ends with the moves before it.
    #[test]
    fn an_error_goes_to_the_reader_that_meets_it() {
        let (mut a, mut b) = tee(program(10, Some(6)));
        assert_eq!(lines(&mut a, 5), vec![1, 2, 3, 4, 5]);
        assert!(a.next().unwrap().is_err());
        assert!(a.next().is_none());
        assert_eq!(lines(&mut b, 10), vec![1, 2, 3, 4, 5]);
        assert!(b.next().is_none());
    }

    /// A reader dropped ahead leaves the other every move it had not read; dropped behind,
    /// nothing more is kept for it.
    #[test]
    fn a_dropped_reader_leaves_the_other_its_moves() {
        let (mut a, mut b) = tee_readers(program(20, None));
        assert_eq!(lines(&mut a, 12).len(), 12);
        assert_eq!(lines(&mut b, 2), vec![1, 2]);
        drop(a);
        assert_eq!(lines(&mut b, 100), (3..=20).collect::<Vec<_>>());

        let (mut a, b) = tee_readers(program(20, None));
        assert_eq!(lines(&mut a, 5).len(), 5);
        drop(b);
        assert_eq!(lines(&mut a, 100), (6..=20).collect::<Vec<_>>());
        assert!(a.shared.borrow().kept.is_empty());
    }
}
