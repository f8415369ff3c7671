//! A block read once into its typed words: the G codes by modal group, the M codes, and
//! each other letter's word, checked for the rules every control shares (one code per
//! modal group, one word per letter). This is the seam between a front end and the
//! interpreter: whatever the program's syntax, the phases of crate `interp` read a
//! [`Block`].

use crate::axis::Axis;
use crate::code::{m_group, GCode, NonModal};
use crate::dialect::parse_g_code;
use crate::lex::{LineError, LineResult, Word, EXPECTED_WORDS};
use crate::options::Dialect;

/// One block's words, typed, and what the phases derive from them as they run.
pub(crate) struct Block<'l> {
    pub line: &'l str,
    pub words: &'l [Word<'l>],
    /// The G codes, at most one per modal group (G4 beside G0-G3 in LinuxCNC).
    pub g: Small<(GCode, Word<'l>), 16>,
    /// The M codes, at most one per M group.
    pub m: Small<(u32, Word<'l>), 16>,
    /// Per letter (see [`slot`]), the index in `words` of its word; [`NONE`] when absent.
    single: [u8; 28],
    /// The letters present, as bits `1 << slot`: a plain block skips each check of a
    /// feature whose letters it has not.
    pub present: u32,
    /// LinuxCNC `$n`: the spindle M3/M4/M5/M19/S act on (one spindle simulated).
    pub spindle_select: Option<Word<'l>>,
    /// G7 in effect: [`Block::get`] halves X (a diameter).
    pub halve_x: bool,
    /// X and Y from polar words `@` `^`, once the motion phase resolved them.
    pub polar: Option<[Option<Word<'l>>; 2]>,
    /// The polar word (`@`, else `^`) when the block has one.
    pub polar_word: Option<Word<'l>>,
    /// Polar words left for a G91 canned cycle to apply at each repeat.
    pub polar_cycle: bool,
    /// The axis words in [`Axis::ALL`] order, X halved under G7, X Y from polar words.
    pub axis: Small<(Axis, Word<'l>), 9>,
    /// The block's F word.
    pub feed_word: Option<Word<'l>>,
    /// The axis words were used by a code other than the motion (G10, G28, G43.1, G68.2,
    /// G5.2 ...).
    pub axes_used: bool,
}

/// No word for this letter in the block.
const NONE: u8 = u8::MAX;

impl<'l> Block<'l> {
    /// Reads `words` (of `line`) into typed words: G codes by `dialect`'s table, M codes as
    /// whole numbers, each other letter once. Errors name the first offending word.
    pub fn read(line: &'l str, words: &'l [Word<'l>], dialect: Dialect) -> LineResult<Block<'l>> {
        if words.len() > 64 {
            let w = words[64];
            return Err(LineError::new(
                w.span(),
                "more than 64 words in a block: expected a shorter block",
                "too many words",
            ));
        }
        let mut b = Block {
            line,
            words,
            g: Small::new(),
            m: Small::new(),
            single: [NONE; 28],
            present: 0,
            spindle_select: None,
            halve_x: false,
            polar: None,
            polar_word: None,
            polar_cycle: false,
            axis: Small::new(),
            feed_word: None,
            axes_used: false,
        };
        for (k, word) in words.iter().enumerate() {
            match word.letter {
                '$' => b.spindle_selector(word)?,
                'G' => b.g_code(word, dialect)?,
                'M' => b.m_code(word)?,
                'O' => {
                    return Err(LineError::new(
                        word.span(),
                        "`O` inside a block: expected an o-word only at the start of a line",
                        "misplaced O",
                    ));
                }
                crate::lex::CORNER_ROUND | crate::lex::CORNER_CHAMFER => {
                    // Read by the reader's stream only (crate::corner), not in a lathe
                    // cycle's shape or a block another front end builds.
                    return Err(LineError::new(
                        word.span(),
                        format!(
                            "`{}` here: corner rounding and chamfer are read only between two G01 blocks of the program itself",
                            &line[word.span()]
                        ),
                        "corner rounding or chamfer",
                    )
                    .help("write the rounding as a G02/G03 arc, or the chamfer as a G01 move"));
                }
                letter => {
                    let slot = &mut b.single[slot(letter)];
                    if let Some(first) = words.get(*slot as usize) {
                        return Err(LineError::new(word.span(), format!("repeated `{letter}` word (first `{}`): expected each of {EXPECTED_WORDS} at most once per block, apart from G and M", &line[first.span()]), "repeated word"));
                    }
                    *slot = k as u8;
                    b.present |= 1 << self::slot(letter);
                }
            }
        }
        Ok(b)
    }

    /// `$-1` (all spindles) to `$8`, once per block.
    fn spindle_selector(&mut self, word: &Word<'l>) -> LineResult<()> {
        let ok = word.value.fract() == 0.0 && (-1.0..=8.0).contains(&word.value);
        if !ok || self.spindle_select.replace(*word).is_some() {
            return Err(LineError::new(
                word.span(),
                "expected one spindle selector `$-1`-`$8` per block",
                "spindle selector",
            ));
        }
        Ok(())
    }

    fn g_code(&mut self, word: &Word<'l>, dialect: Dialect) -> LineResult<()> {
        let line = self.line;
        let g = &mut self.g;
        let code = parse_g_code(word, line, dialect.table())?;
        // LinuxCNC accepts G80 beside G00/G01 (`G80 G0 Z10`): the cancel is implied.
        let g80 = GCode::Motion(None);
        if matches!(code, GCode::Motion(None))
            && g.iter().any(|(c, _)| matches!(c, GCode::Motion(Some(_))))
        {
            return Ok(());
        }
        if let Some(k) = g.iter().position(|(c, _)| *c == g80) {
            if matches!(code, GCode::Motion(Some(_))) {
                g.remove(k);
            }
        }
        // LinuxCNC: G4 is non-modal (group 0) and may share a block with G0-G3.
        let dwell_pair = |a: GCode, b: GCode| {
            dialect.table().dwell_beside_motion
                && (a == GCode::NonModal(NonModal::Dwell))
                    != (b == GCode::NonModal(NonModal::Dwell))
        };
        if let Some((_, other)) = g
            .iter()
            .find(|(c, _)| c.group() == code.group() && !dwell_pair(*c, code))
        {
            return Err(LineError::new(
                word.span(),
                format!(
                    "`{}` and `{}` are in the same modal group: expected at most one per block",
                    &line[other.span()],
                    &line[word.span()]
                ),
                "second code of the group",
            )
            .help("split them into two blocks"));
        }
        if !g.push((code, *word)) {
            return Err(LineError::new(
                word.span(),
                "more than 16 G codes in a block: expected at most one per modal group",
                "too many G codes",
            ));
        }
        Ok(())
    }

    fn m_code(&mut self, word: &Word<'l>) -> LineResult<()> {
        let line = self.line;
        let code = integer(word, line)? as u32;
        let grp = m_group(code);
        if let Some((_, other)) = self
            .m
            .iter()
            .find(|(c, _)| grp.is_some() && m_group(*c) == grp)
        {
            return Err(LineError::new(
                word.span(),
                format!(
                    "`{}` and `{}` are in the same group: expected at most one per block",
                    &line[other.span()],
                    &line[word.span()]
                ),
                "second code of the group",
            ));
        }
        if !self.m.push((code, *word)) {
            return Err(LineError::new(
                word.span(),
                "more than 16 M codes in a block: expected fewer",
                "too many M codes",
            ));
        }
        Ok(())
    }

    /// The word of `letter` as the phases read it: X halved under G7 (a diameter); after
    /// the motion phase resolved polar words, X and Y from them.
    #[inline]
    pub fn get(&self, l: char) -> Option<Word<'l>> {
        match (l, &self.polar) {
            ('X', Some([Some(x), _])) => Some(*x),
            ('Y', Some([_, Some(y)])) => Some(*y),
            _ => self.written(l),
        }
    }

    /// The word of `letter` as written (X halved under G7), before polar words.
    #[inline]
    pub fn written(&self, l: char) -> Option<Word<'l>> {
        self.words
            .get(self.single[slot(l)] as usize)
            .copied()
            .map(|mut w| {
                if self.halve_x && l == 'X' {
                    w.value /= 2.0;
                }
                w
            })
    }

    /// The word at `slot` as written in the block (not halved), when present.
    #[inline]
    pub fn at_slot(&self, k: usize) -> &Word<'l> {
        &self.words[self.single[k] as usize]
    }

    /// Whether the block has any of the letters of `mask` ([`letters`]).
    #[inline]
    pub fn has_any(&self, mask: u32) -> bool {
        self.present & mask != 0
    }

    /// Whether a G code of the block satisfies `f`.
    pub fn has_g(&self, f: impl Fn(&GCode) -> bool) -> bool {
        self.g.iter().any(|(c, _)| f(c))
    }

    /// Whether the block has M `code`.
    pub fn has_m(&self, code: u32) -> bool {
        self.m.iter().any(|(c, _)| *c == code)
    }

    /// The block's non-modal code (group 0) and its word.
    pub fn nonmodal(&self) -> Option<(NonModal, Word<'l>)> {
        self.g.iter().find_map(|(c, w)| match c {
            GCode::NonModal(n) => Some((*n, *w)),
            _ => None,
        })
    }

    /// The block's motion code (group 1) and its word; `Some((None, _))` is G80.
    pub fn motion_code(&self) -> Option<(Option<crate::code::MotionMode>, Word<'l>)> {
        self.g.iter().find_map(|(c, w)| match c {
            GCode::Motion(mm) => Some((*mm, *w)),
            _ => None,
        })
    }
}

/// A vector of at most `N` copies, on the stack, its slots not initialised until pushed
/// (docs/performance.md: the reader's block buffers).
pub(crate) struct Small<T: Copy, const N: usize> {
    items: [std::mem::MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Small<T, N> {
    pub(crate) fn new() -> Self {
        Small {
            items: [const { std::mem::MaybeUninit::uninit() }; N],
            len: 0,
        }
    }
    /// False when full.
    #[inline(always)]
    pub(crate) fn push(&mut self, t: T) -> bool {
        if self.len == N {
            return false;
        }
        self.items[self.len] = std::mem::MaybeUninit::new(t);
        self.len += 1;
        true
    }
    pub(crate) fn remove(&mut self, k: usize) {
        self.items.copy_within(k + 1..self.len, k);
        self.len -= 1;
    }
}

impl<'l, const N: usize> Small<(Axis, Word<'l>), N> {
    /// Pushes `(axis, *word)`, the value halved when `halve`, written field by field
    /// (docs/performance.md: the reader's block buffers).
    #[inline(always)]
    pub(crate) fn push_axis(&mut self, axis: Axis, word: &Word<'l>, halve: bool) {
        let slot = self.items[self.len].as_mut_ptr();
        // SAFETY: `slot` points to an item of `items` (indexing checked `len` < N); both
        // fields are written here, so the item is initialised before `len` counts it.
        unsafe {
            std::ptr::addr_of_mut!((*slot).0).write(axis);
            std::ptr::addr_of_mut!((*slot).1).write(*word);
            if halve {
                (*slot).1.value /= 2.0;
            }
        }
        self.len += 1;
    }
}

impl<T: Copy, const N: usize> std::ops::Deref for Small<T, N> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        // SAFETY: `push` wrote items 0..len (and `remove` keeps them written), and
        // `MaybeUninit<T>` has the layout of `T`.
        unsafe { std::slice::from_raw_parts(self.items.as_ptr().cast::<T>(), self.len) }
    }
}

/// Index of a word letter in a block's table of single words: A-Z, then `@` and `^`.
pub(crate) const fn slot(letter: char) -> usize {
    match letter {
        '@' => 26,
        '^' => 27,
        l => (l as u8 - b'A') as usize,
    }
}

/// The bits (`1 << slot`) of `letters`.
pub(crate) const fn letters(letters: &[char]) -> u32 {
    let mut mask = 0;
    let mut k = 0;
    while k < letters.len() {
        mask |= 1 << slot(letters[k]);
        k += 1;
    }
    mask
}

/// The value of `word` as a non-negative integer.
pub(crate) fn integer(word: &Word, line: &str) -> LineResult<u64> {
    let bad = || {
        LineError::new(
            word.span(),
            format!(
                "`{}`: expected a whole number after `{}`",
                &line[word.span()],
                word.letter
            ),
            "expected a whole number",
        )
    };
    if word.computed() {
        if word.value < 0.0 || (word.value - word.value.round()).abs() > 1e-4 || word.value > 1e15 {
            return Err(bad());
        }
        return Ok(word.value.round() as u64);
    }
    let digits = word.number.strip_prefix('+').unwrap_or(word.number);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) || digits.len() > 15 {
        return Err(bad());
    }
    Ok(word.value as u64)
}
