//! The moves of a G-code program (G0/G1 with G90/G91, M82/M83, G92, G20/G21), as the
//! checker reads them.

use std::borrow::Cow;

use glam::DVec3;

use super::limits::truncated;

/// A G-code file that cannot be read as G-code.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct GcodeError {
    pub line: usize,
    pub message: String,
}

/// One positioning move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    pub to: DVec3,
    /// Filament/clay advanced by this move (negative = retraction).
    pub de: f64,
    /// 1-based line number in the file.
    pub line: usize,
}

/// Parses the moves of a G-code program (G0/G1 with G90/G91, M82/M83, G92, G20/G21).
///
/// Read in two steps: the lines are read in parts, one per core (`read_part`: the words and
/// numbers of each line, which need no state), then the modal state (G90/G91, M82/M83, G92,
/// G28) is applied to the moves in file order (`Part::resolve`). The moves and the first error
/// are those of reading the whole file line by line (tested).
pub fn parse_moves(text: &str) -> Result<(Vec<Move>, DVec3), GcodeError> {
    let cores = crate::parallel::cores().clamp(1, 8);
    parse_moves_in(text, text.len().div_ceil(cores).max(PART_BYTES))
}

/// Bytes of text below which the file is read in one part (a thread costs more).
const PART_BYTES: usize = 1 << 20;

/// [`parse_moves`], in parts of at least `part_bytes` each (whole lines), one thread each.
fn parse_moves_in(text: &str, part_bytes: usize) -> Result<(Vec<Move>, DVec3), GcodeError> {
    let read = read_parts(text, part_bytes);
    let mut state = State::default();
    let mut moves = Vec::new();
    resolve_parts(read, &mut state, 0, &mut moves)?;
    Ok((moves, state.start.unwrap_or(DVec3::ZERO)))
}

/// The lines of `text` read in parts of at least `part_bytes` each (cut after a newline), one
/// thread each, in order.
fn read_parts(text: &str, part_bytes: usize) -> Vec<Part<'static>> {
    let mut texts = Vec::new();
    let mut rest = text;
    let want = part_bytes.max(1);
    while rest.len() > want {
        match rest.as_bytes()[want..].iter().position(|&b| b == b'\n') {
            Some(k) => {
                let (head, tail) = rest.split_at(want + k + 1);
                texts.push(head);
                rest = tail;
            }
            None => break,
        }
    }
    texts.push(rest);
    if texts.len() == 1 {
        vec![read_part(text)]
    } else {
        crate::parallel::run_parts(texts.iter().map(|&t| move || read_part(t)).collect())
    }
}

/// Bytes of a piece below which [`MoveReader`] reads it in one part: a piece the writer gives
/// (about 600 kB) is read on both cores, half each (1.3 → 0.7 ms a piece).
const READER_PART_BYTES: usize = 1 << 16;

/// The moves of a G-code program read as its text arrives, in pieces cut anywhere (a program
/// checked while it is written need not be kept whole): each piece's complete lines are read
/// and resolved at once, a cut line waits for its end. The moves and the first error are those
/// of [`parse_moves`] on the whole text (tested).
pub struct MoveReader {
    state: State,
    /// Lines read so far.
    lines: usize,
    /// The start of a line cut by the last piece.
    partial: Vec<u8>,
    moves: Vec<Move>,
    /// The first error; nothing more is read after it.
    error: Option<GcodeError>,
    /// A piece is read in parts of at least this many bytes, one per core.
    part_bytes: usize,
}

impl MoveReader {
    /// A reader with room for `moves` moves.
    pub fn with_capacity(moves: usize) -> Self {
        MoveReader {
            state: State::default(),
            lines: 0,
            partial: Vec::new(),
            moves: Vec::with_capacity(moves),
            error: None,
            part_bytes: READER_PART_BYTES,
        }
    }

    /// Reads the complete lines of `bytes` (with the cut line before them).
    pub fn feed(&mut self, bytes: &[u8]) {
        if self.error.is_some() {
            return;
        }
        let Some(last) = bytes.iter().rposition(|&b| b == b'\n') else {
            self.partial.extend_from_slice(bytes);
            return;
        };
        let (mut lines, rest) = bytes.split_at(last + 1);
        if !self.partial.is_empty() {
            // The cut line, completed, on its own: the rest of the piece is read where it is.
            let end = lines
                .iter()
                .position(|&b| b == b'\n')
                .map_or(lines.len(), |k| k + 1);
            let mut joined = std::mem::take(&mut self.partial);
            joined.extend_from_slice(&lines[..end]);
            self.read(&joined);
            lines = &lines[end..];
        }
        if !lines.is_empty() && self.error.is_none() {
            self.read(lines);
        }
        self.partial.extend_from_slice(rest);
    }

    /// Takes pieces of text, each of whole lines, whose writer tells what they read as: where
    /// a piece has its `moves` and no cut line waits, they are taken as its lines' reading and
    /// the text is not read again; otherwise the text is read ([`MoveReader::feed`]). The
    /// result is the same as feeding the texts when the moves are what [`read_part`] makes of
    /// them (the G-code writer's are: tested in `gcode.rs`).
    pub(crate) fn feed_told(&mut self, pieces: &[ToldPiece<'_>]) {
        if self.error.is_some() {
            return;
        }
        if !self.partial.is_empty() || pieces.iter().any(|p| p.moves.is_none()) {
            pieces.iter().for_each(|p| self.feed(p.text));
            return;
        }
        let parts = pieces
            .iter()
            .map(|p| Part {
                moves: Cow::Borrowed(p.moves.unwrap_or_default()),
                modal: Vec::new(),
                error: None,
                lines: p.lines,
            })
            .collect();
        match resolve_parts(parts, &mut self.state, self.lines, &mut self.moves) {
            Ok(lines) => self.lines += lines,
            Err(e) => self.error = Some(e),
        }
    }

    /// Takes the pieces `run` gives to a [`ToldStream`] (on several threads, as each is
    /// written: see there) as [`MoveReader::feed_told`] would take them in order; `text_at`
    /// says where in the file the first piece's text goes and `moves` how many moves the pieces
    /// hold (room for more is not made: a piece that does not fit is an error). Gives where the
    /// last piece's text ends; none, with `run` not run, where a line cut by the text before
    /// waits for the first piece, or reading has stopped at an error.
    pub(crate) fn stream_told(
        &mut self,
        text_at: u64,
        moves: usize,
        run: impl FnOnce(&ToldStream<'_>),
    ) -> Option<u64> {
        if self.error.is_some() || !self.partial.is_empty() {
            return None;
        }
        self.moves.reserve(moves);
        let len = self.moves.len();
        let stream = ToldStream {
            chain: std::sync::Mutex::new(Chain {
                next: 0,
                state: self.state,
                lines: self.lines,
                text_at,
                room: &mut self.moves.spare_capacity_mut()[..moves],
            }),
            abandoned: std::sync::atomic::AtomicBool::new(false),
            resolved: std::sync::Mutex::new(Vec::new()),
        };
        run(&stream);
        let chain = stream.chain.into_inner().unwrap_or_else(|e| e.into_inner());
        let (state, lines, text_end) = (chain.state, chain.lines, chain.text_at);
        let mut resolved = stream
            .resolved
            .into_inner()
            .unwrap_or_else(|e| e.into_inner());
        resolved.sort_unstable_by_key(|r| r.0);
        // The moves of the pieces in order up to the first that failed (or was never taken):
        // each before it wrote its whole stretch, that one the first `written` of its own.
        let mut written_total = 0;
        for (expected, (k, written, result)) in resolved.into_iter().enumerate() {
            if k != expected {
                break;
            }
            written_total += written;
            if let Err(e) = result {
                self.error = Some(e);
                break;
            }
        }
        // SAFETY: `written_total` contiguous moves from `len` on were initialised (above).
        unsafe { self.moves.set_len(len + written_total) };
        (self.state, self.lines) = (state, lines);
        Some(text_end)
    }

    /// The moves and where the first starts, once the whole text is in.
    pub fn finish(mut self) -> Result<(Vec<Move>, DVec3), GcodeError> {
        let rest = std::mem::take(&mut self.partial);
        if !rest.is_empty() && self.error.is_none() {
            self.read(&rest);
        }
        match self.error {
            Some(e) => Err(e),
            None => Ok((self.moves, self.state.start.unwrap_or(DVec3::ZERO))),
        }
    }

    /// Reads whole lines (a line cut only at the end of the text).
    fn read(&mut self, lines: &[u8]) {
        // A newline is never part of a multi-byte character: each piece of whole lines is text
        // or not on its own.
        let text = match std::str::from_utf8(lines) {
            Ok(t) => t,
            Err(e) => {
                let line = self.lines
                    + 1
                    + lines[..e.valid_up_to()]
                        .iter()
                        .filter(|&&b| b == b'\n')
                        .count();
                self.error = Some(GcodeError {
                    line,
                    message: "not text (UTF-8)".into(),
                });
                return;
            }
        };
        let cores = crate::parallel::cores();
        let parts = read_parts(text, self.part_bytes.max(text.len().div_ceil(cores)));
        match resolve_parts(parts, &mut self.state, self.lines, &mut self.moves) {
            Ok(lines) => self.lines += lines,
            Err(e) => self.error = Some(e),
        }
    }
}

/// A piece of a program as its writer gives it: its text (whole lines, `lines` of them) and,
/// where the writer can tell them, the moves its lines read as before the modal state (`to` the
/// X Y Z given, `de` the E given, NaN where not given; `line` counted from 1 in the piece),
/// with no line that changes a mode.
pub(crate) struct ToldPiece<'a> {
    pub text: &'a [u8],
    pub moves: Option<&'a [Move]>,
    pub lines: usize,
}

/// The body's pieces taken as they are written, on the threads that wrote them
/// ([`MoveReader::stream_told`]). A thread that has written piece k into a buffer of its own
/// gives it to [`ToldStream::take`], which places it after the pieces before it (the file
/// offset of its text, its first line, the state it starts from, its stretch of the moves) and
/// resolves its moves there, on that thread: each core reads what it wrote, from its own cache,
/// and writes the next piece into the same buffer with no other core holding those lines. Two
/// cores that share no cache (a virtual machine's, placed on different processor dies) pass a
/// line written by one to the other at several times the cost of a read from memory: with one
/// core writing the whole text to the file and the other resolving all the moves, the next
/// round's formatting took three times as long.
pub(crate) struct ToldStream<'r> {
    /// Where the next piece goes; only piece `next` may be placed.
    chain: std::sync::Mutex<Chain<'r>>,
    /// Set when some piece will never be taken (its writer failed): the others stop waiting.
    abandoned: std::sync::atomic::AtomicBool,
    /// Each piece taken: how many of its moves were resolved, and its first error.
    resolved: std::sync::Mutex<Vec<Resolved>>,
}

/// A piece taken by a [`ToldStream`]: its number, how many of its moves were resolved, and its
/// first error.
type Resolved = (usize, usize, Result<(), GcodeError>);

/// Where the pieces placed so far end.
struct Chain<'r> {
    /// The next piece to place.
    next: usize,
    /// The modal state after them, their lines, and where the next piece's text goes.
    state: State,
    lines: usize,
    text_at: u64,
    /// Room for the next pieces' moves.
    room: &'r mut [std::mem::MaybeUninit<Move>],
}

impl ToldStream<'_> {
    /// Takes piece `k` (each of 0, 1, 2 … once, from any thread; a thread that takes several
    /// takes them in order, as it must not wait for one it will take later): waits until the
    /// pieces before it are placed, places it, has `write(offset)` put its text at that
    /// file offset and resolves its moves into their place. A piece that does not tell its
    /// moves is read here.
    pub(crate) fn take(&self, k: usize, piece: &ToldPiece<'_>, write: impl FnOnce(u64)) {
        use std::sync::atomic::Ordering;
        let part = match piece.moves {
            Some(moves) => Part {
                moves: Cow::Borrowed(moves),
                modal: Vec::new(),
                error: None,
                lines: piece.lines,
            },
            None => match std::str::from_utf8(piece.text) {
                Ok(text) => read_part(text),
                Err(_) => Part {
                    moves: Cow::Borrowed(&[]),
                    modal: Vec::new(),
                    error: Some(GcodeError {
                        line: 1,
                        message: "not text (UTF-8)".into(),
                    }),
                    lines: piece.lines,
                },
            },
        };
        let mut spins = 0u32;
        let mut chain = loop {
            let chain = self.chain.lock().unwrap_or_else(|e| e.into_inner());
            if chain.next == k {
                break chain;
            }
            drop(chain);
            if self.abandoned.load(Ordering::Relaxed) {
                return;
            }
            // The piece before is being written on another core: a few microseconds mostly.
            spins = spins.wrapping_add(1);
            if spins.is_multiple_of(64) {
                std::thread::yield_now();
            } else {
                std::hint::spin_loop();
            }
        };
        let (start, first_line, offset) = (chain.state, chain.lines, chain.text_at);
        let room = std::mem::take(&mut chain.room);
        let fits = part.moves.len() <= room.len();
        let (stretch, rest) = room.split_at_mut(part.moves.len().min(room.len()));
        chain.room = rest;
        chain.next += 1;
        chain.lines += part.lines;
        chain.text_at += piece.text.len() as u64;
        let mut end = start;
        let outcome = match part.state_after(&start) {
            _ if !fits => {
                drop(chain);
                write(offset);
                let error = GcodeError {
                    line: first_line + 1,
                    message: "more moves than the writer said".into(),
                };
                (0, Err(error))
            }
            // Told from the raw moves: the next piece may be placed while this one resolves.
            Some(after) => {
                chain.state = after;
                drop(chain);
                write(offset);
                part.resolve_into(&mut end, first_line, stretch)
            }
            // A mode changes within it (or positions are relative): resolved in turn.
            None => {
                let resolved = part.resolve_into(&mut end, first_line, stretch);
                chain.state = end;
                drop(chain);
                write(offset);
                resolved
            }
        };
        self.resolved
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push((k, outcome.0, outcome.1));
    }

    /// Stops every wait for a piece: some piece will never be taken.
    pub(crate) fn abandon(&self) {
        self.abandoned
            .store(true, std::sync::atomic::Ordering::Relaxed);
    }
}

/// What changes the modal state, read from one line.
#[derive(Debug, Clone, Copy)]
enum Modal {
    AbsoluteXyz(bool),
    AbsoluteE(bool),
    /// G92: the axes given (NaN: not given), X Y Z E.
    SetPosition([f64; 4]),
    /// G28.
    Home,
}

/// One part of the file as read without the modal state.
struct Part<'a> {
    /// Its moves: `to` the X Y Z given and `de` the E given (NaN where not given), `line` within
    /// the part: read here, or told by the writer of the text ([`MoveReader::feed_told`]).
    moves: Cow<'a, [Move]>,
    /// The state changes, each before move `.0` of the part.
    modal: Vec<(usize, Modal)>,
    /// The first error, after all the part's moves.
    error: Option<GcodeError>,
    /// Lines in the part.
    lines: usize,
}

/// The modal state, as the file sets it up to a line.
#[derive(Clone, Copy)]
struct State {
    pos: DVec3,
    e: f64,
    absolute_xyz: bool,
    absolute_e: bool,
    /// Where the first move starts.
    start: Option<DVec3>,
}

impl Default for State {
    fn default() -> Self {
        Self {
            pos: DVec3::ZERO,
            e: 0.0,
            absolute_xyz: true,
            absolute_e: true,
            start: None,
        }
    }
}

impl State {
    fn apply(&mut self, modal: Modal) {
        match modal {
            Modal::AbsoluteXyz(on) => self.absolute_xyz = on,
            Modal::AbsoluteE(on) => self.absolute_e = on,
            Modal::SetPosition([x, y, z, e]) => {
                if !e.is_nan() {
                    self.e = e;
                }
                for (c, v) in [x, y, z].into_iter().enumerate() {
                    if !v.is_nan() {
                        self.pos[c] = v;
                    }
                }
            }
            Modal::Home => self.pos = DVec3::ZERO,
        }
    }
}

/// Resolves `parts` (read from consecutive text, the first starting after `lines_before`
/// lines) into `out` in order, as [`Part::resolve_into`] one after another would, and gives the
/// number of lines read.
///
/// Where each part's starting state can be told from the raw moves before it
/// ([`Part::state_after`]: no modal command, absolute positions, as in the body of a program
/// the writer makes), those parts are resolved at the same time, one per core, each into its
/// own stretch of `out`: the moves are copied out and their pages faulted in on both cores.
fn resolve_parts(
    mut parts: Vec<Part<'_>>,
    state: &mut State,
    lines_before: usize,
    out: &mut Vec<Move>,
) -> Result<usize, GcodeError> {
    out.reserve(parts.iter().map(|p| p.moves.len()).sum());
    // The parts from `together` on change no mode but perhaps the last: they can start
    // together once the ones before are resolved (if positions are absolute then).
    let last = parts.len().saturating_sub(1);
    let together = parts[..last]
        .iter()
        .rposition(|p| !p.modal.is_empty())
        .map_or(0, |k| k + 1);
    let later = parts.split_off(together);
    let mut lines = resolve_in_turn(parts, state, lines_before, out)?;
    if later.len() < 2 || !state.absolute_xyz {
        return Ok(resolve_in_turn(later, state, lines, out)? - lines_before);
    }
    // Each part's starting state and first line, then one stretch of the spare capacity each.
    let len = out.len();
    let mut spare = &mut out.spare_capacity_mut()[..];
    let last = later.len() - 1;
    let mut jobs = Vec::with_capacity(later.len());
    let mut ahead = *state;
    for (k, part) in later.into_iter().enumerate() {
        let first_line = lines;
        lines += part.lines;
        let mut start = ahead;
        // Told for every part but the last (it changes no mode; positions stay absolute).
        let after = part.state_after(&ahead);
        debug_assert!(after.is_some() || k == last);
        ahead = after.unwrap_or(ahead);
        let (stretch, rest) = std::mem::take(&mut spare).split_at_mut(part.moves.len());
        spare = rest;
        jobs.push(move || {
            let (written, result) = part.resolve_into(&mut start, first_line, stretch);
            (written, result, start)
        });
    }
    let mut written_total = 0;
    let mut outcome = Ok(lines - lines_before);
    for (written, result, end) in crate::parallel::run_parts(jobs) {
        written_total += written;
        *state = end;
        if let Err(e) = result {
            outcome = Err(e);
            break;
        }
    }
    // SAFETY: the parts before the first that failed wrote their whole stretches, and that one
    // the first `written` slots of its own: `written_total` contiguous initialised moves.
    unsafe { out.set_len(len + written_total) };
    outcome
}

/// Resolves `parts` one after another into `out` (room reserved), the first starting after
/// `lines` lines; gives the lines read up to the end of the last.
fn resolve_in_turn(
    parts: Vec<Part<'_>>,
    state: &mut State,
    mut lines: usize,
    out: &mut Vec<Move>,
) -> Result<usize, GcodeError> {
    for part in parts {
        let count = part.lines;
        let (written, result) = part.resolve_into(state, lines, out.spare_capacity_mut());
        // SAFETY: `resolve_into` initialised the first `written` slots of the spare capacity.
        unsafe { out.set_len(out.len() + written) };
        result?;
        lines += count;
    }
    Ok(lines)
}

impl Part<'_> {
    /// Applies the modal state to the part's moves in order, writing them to the start of
    /// `out` (room for all of them) with their lines counted from the file's start; `state`
    /// is left as the part leaves it. Gives how many moves were written (all but after an
    /// error), with the part's first error.
    fn resolve_into(
        self,
        state: &mut State,
        lines_before: usize,
        out: &mut [std::mem::MaybeUninit<Move>],
    ) -> (usize, Result<(), GcodeError>) {
        let count = self.moves.len();
        assert!(out.len() >= count, "room for every move of the part");
        let mut modal = self.modal.iter().peekable();
        for ((k, &m), slot) in self.moves.iter().enumerate().zip(out.iter_mut()) {
            while let Some((_, change)) = modal.next_if(|(at, _)| *at == k) {
                state.apply(*change);
            }
            let line = m.line + lines_before;
            let mut to = state.pos;
            for c in 0..3 {
                let v = m.to[c];
                if !v.is_nan() {
                    to[c] = if state.absolute_xyz { v } else { to[c] + v };
                }
            }
            let de = match m.de {
                v if v.is_nan() => 0.0,
                v if state.absolute_e => {
                    let d = v - state.e;
                    state.e = v;
                    d
                }
                v => v,
            };
            if !to.is_finite() {
                let error = GcodeError {
                    line,
                    message: "the position runs past any finite number".into(),
                };
                return (k, Err(error));
            }
            state.start.get_or_insert(state.pos);
            slot.write(Move { to, de, line });
            state.pos = to;
        }
        for (_, change) in modal {
            state.apply(*change);
        }
        match self.error {
            Some(e) => (
                count,
                Err(GcodeError {
                    line: e.line + lines_before,
                    ..e
                }),
            ),
            None => (count, Ok(())),
        }
    }

    /// The state [`Part::resolve_into`] leaves, from `state`, told without resolving the moves:
    /// where the part changes no mode and its X, Y and Z are absolute, each axis ends at the
    /// last value given for it (E too, when absolute). None otherwise.
    fn state_after(&self, state: &State) -> Option<State> {
        if !self.modal.is_empty() || !state.absolute_xyz {
            return None;
        }
        let mut after = *state;
        let mut missing = [true; 4];
        for m in self.moves.iter().rev() {
            for (c, v) in [m.to.x, m.to.y, m.to.z, m.de].into_iter().enumerate() {
                if missing[c] && !v.is_nan() {
                    missing[c] = false;
                    match c {
                        3 if state.absolute_e => after.e = v,
                        3 => {}
                        _ => after.pos[c] = v,
                    }
                }
            }
            if missing == [false; 4] {
                break;
            }
        }
        if !self.moves.is_empty() {
            after.start = Some(state.start.unwrap_or(state.pos));
        }
        Some(after)
    }
}

/// Reads the lines of `text` without the modal state (see [`Part`]); stops at the first error.
fn read_part(text: &str) -> Part<'static> {
    let mut part = Part {
        moves: Cow::Owned(Vec::with_capacity(text.len() / 40)),
        modal: Vec::new(),
        error: None,
        lines: 0,
    };
    if let Err(e) = read_lines(text, &mut part) {
        part.error = Some(e);
    }
    part
}

/// The command of a G-code line and the first word of each axis letter after it (X, Y, Z, E),
/// found in one pass over the line (each is parsed only where the command reads it). None for a
/// line with no command: blank, a comment, a bare line number. The comment and a host checksum
/// (`*nn`) are dropped; a line number (`N12 G1 …`) before the command is passed over.
fn words_of(raw: &str) -> Option<(&str, [Option<&str>; 4])> {
    let code = raw
        .split(';')
        .next()
        .unwrap_or("")
        .split('*')
        .next()
        .unwrap_or("")
        .trim();
    let mut words = code.split_whitespace();
    let mut cmd = words.next()?;
    let mut letters: [Option<&str>; 4] = [None; 4];
    let mut numbered = cmd.starts_with(['N', 'n']) && cmd[1..].parse::<u64>().is_ok();
    for w in words {
        if numbered {
            cmd = w;
            numbered = false;
        }
        let slot = match w.as_bytes()[0].to_ascii_uppercase() {
            b'X' => 0,
            b'Y' => 1,
            b'Z' => 2,
            b'E' => 3,
            _ => continue,
        };
        letters[slot].get_or_insert(w);
    }
    (!numbered).then_some((cmd, letters))
}

/// A move in the form the G-code writer gives every path point (`G1 X… Y… Z… E… F…`: upper
/// case, one space before each word, plain decimals, each letter at most once, nothing else on
/// the line), read in one pass over its bytes: the X, Y, Z and E given (NaN where not given),
/// each read by [`crate::decimal::plain_decimal`], as [`words_of`]'s numbers are. None for any
/// other line, which [`words_of`] reads (tested: both read alike).
fn plain_move(raw: &[u8]) -> Option<[f64; 4]> {
    let rest = raw
        .strip_prefix(b"G1 ")
        .or_else(|| raw.strip_prefix(b"G0 "))?;
    let mut given = [f64::NAN; 5];
    let mut seen = [false; 5];
    // Word by word: a letter, a number read up to where it ends, then a space or the end.
    let mut word = rest;
    loop {
        let (&letter, number) = word.split_first()?;
        let slot = match letter {
            b'X' => 0,
            b'Y' => 1,
            b'Z' => 2,
            b'E' => 3,
            b'F' => 4,
            _ => return None,
        };
        if std::mem::replace(&mut seen[slot], true) {
            return None;
        }
        let (v, used) = crate::decimal::decimal_prefix(number)?;
        given[slot] = v;
        match number.get(used) {
            None => break,
            Some(b' ') => word = &number[used + 1..],
            Some(_) => return None,
        }
    }
    Some([given[0], given[1], given[2], given[3]])
}

fn read_lines(text: &str, part: &mut Part<'_>) -> Result<(), GcodeError> {
    let moves = part.moves.to_mut();
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        part.lines = line;
        if let Some([x, y, z, e]) = plain_move(raw.as_bytes()) {
            moves.push(Move {
                to: DVec3::new(x, y, z),
                de: e,
                line,
            });
            continue;
        }
        let Some((cmd, letters)) = words_of(raw) else {
            continue;
        };
        let arg = |letter: char| -> Result<Option<f64>, GcodeError> {
            let slot = match letter {
                'X' => 0,
                'Y' => 1,
                'Z' => 2,
                _ => 3,
            };
            let Some(w) = letters[slot] else {
                return Ok(None);
            };
            let v = crate::decimal::parse_f64(&w[1..]).map_err(|_| GcodeError {
                line,
                message: format!("`{}` is not a number", truncated(w)),
            })?;
            if !v.is_finite() {
                return Err(GcodeError {
                    line,
                    message: format!("`{}` is not finite", truncated(w)),
                });
            }
            Ok(Some(v))
        };
        let is = |name: &str| cmd.eq_ignore_ascii_case(name);
        let given = |v: Option<f64>| v.unwrap_or(f64::NAN);
        if is("G1") || is("G0") || is("G01") || is("G00") {
            let (x, y, z, ev) = (arg('X')?, arg('Y')?, arg('Z')?, arg('E')?);
            moves.push(Move {
                to: DVec3::new(given(x), given(y), given(z)),
                de: given(ev),
                line,
            });
        } else if is("G90") {
            part.modal.push((moves.len(), Modal::AbsoluteXyz(true)));
        } else if is("G91") {
            part.modal.push((moves.len(), Modal::AbsoluteXyz(false)));
        } else if is("M82") {
            part.modal.push((moves.len(), Modal::AbsoluteE(true)));
        } else if is("M83") {
            part.modal.push((moves.len(), Modal::AbsoluteE(false)));
        } else if is("G92") {
            let e = arg('E')?;
            let (x, y, z) = (arg('X')?, arg('Y')?, arg('Z')?);
            part.modal.push((
                moves.len(),
                Modal::SetPosition([given(x), given(y), given(z), given(e)]),
            ));
        } else if is("G20") {
            return Err(GcodeError {
                line,
                message: "inch units (G20) are not supported".into(),
            });
        } else if is("G28") {
            part.modal.push((moves.len(), Modal::Home));
        } else if cmd.starts_with(['G', 'M', 'T', 'N', 'F', 'S', 'g', 'm', 't', 'n', 'f', 's'])
            && cmd[1..].parse::<f64>().is_ok()
        {
            // Other numbered commands: no moves.
        } else if cmd.len() >= 3
            && cmd.starts_with(|c: char| c.is_ascii_uppercase())
            && cmd
                .chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
        {
            // Klipper's and RepRapFirmware's named commands (`SET_PRINT_STATS_INFO …`,
            // `TURN_OFF_HEATERS`): no moves.
        } else {
            return Err(GcodeError {
                line,
                message: format!(
                    "`{}` is not a G-code command",
                    truncated(&cmd.to_ascii_uppercase())
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The reader as it was before it read in parts: one pass, line by line, with the modal
    /// state. The reference the parts must match.
    fn parse_moves_reference(text: &str) -> Result<(Vec<Move>, DVec3), GcodeError> {
        let mut moves = Vec::new();
        let mut pos = DVec3::ZERO;
        let mut start = None;
        let mut e = 0.0;
        let (mut absolute_xyz, mut absolute_e) = (true, true);
        for (idx, raw) in text.lines().enumerate() {
            let line = idx + 1;
            let Some((cmd, letters)) = words_of(raw) else {
                continue;
            };
            let arg = |letter: char| -> Result<Option<f64>, GcodeError> {
                let slot = match letter {
                    'X' => 0,
                    'Y' => 1,
                    'Z' => 2,
                    _ => 3,
                };
                let Some(w) = letters[slot] else {
                    return Ok(None);
                };
                let v: f64 = w[1..].parse().map_err(|_| GcodeError {
                    line,
                    message: format!("`{}` is not a number", truncated(w)),
                })?;
                if !v.is_finite() {
                    return Err(GcodeError {
                        line,
                        message: format!("`{}` is not finite", truncated(w)),
                    });
                }
                Ok(Some(v))
            };
            let is = |name: &str| cmd.eq_ignore_ascii_case(name);
            if is("G1") || is("G0") || is("G01") || is("G00") {
                let (x, y, z, ev) = (arg('X')?, arg('Y')?, arg('Z')?, arg('E')?);
                let mut to = pos;
                for (v, c) in [(x, 0), (y, 1), (z, 2)] {
                    if let Some(v) = v {
                        to[c] = if absolute_xyz { v } else { to[c] + v };
                    }
                }
                let de = match ev {
                    Some(v) if absolute_e => {
                        let d = v - e;
                        e = v;
                        d
                    }
                    Some(v) => v,
                    None => 0.0,
                };
                if !to.is_finite() {
                    return Err(GcodeError {
                        line,
                        message: "the position runs past any finite number".into(),
                    });
                }
                if start.is_none() {
                    start = Some(pos);
                }
                moves.push(Move { to, de, line });
                pos = to;
            } else if is("G90") {
                absolute_xyz = true;
            } else if is("G91") {
                absolute_xyz = false;
            } else if is("M82") {
                absolute_e = true;
            } else if is("M83") {
                absolute_e = false;
            } else if is("G92") {
                if let Some(v) = arg('E')? {
                    e = v;
                }
                for (letter, c) in [('X', 0), ('Y', 1), ('Z', 2)] {
                    if let Some(v) = arg(letter)? {
                        pos[c] = v;
                    }
                }
            } else if is("G20") {
                return Err(GcodeError {
                    line,
                    message: "inch units (G20) are not supported".into(),
                });
            } else if is("G28") {
                pos = DVec3::ZERO;
            } else if cmd.starts_with(['G', 'M', 'T', 'N', 'F', 'S', 'g', 'm', 't', 'n', 'f', 's'])
                && cmd[1..].parse::<f64>().is_ok()
            {
                // Other numbered commands: no moves.
            } else if cmd.len() >= 3
                && cmd.starts_with(|c: char| c.is_ascii_uppercase())
                && cmd
                    .chars()
                    .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
            {
                // Klipper's and RepRapFirmware's named commands (`SET_PRINT_STATS_INFO …`,
                // `TURN_OFF_HEATERS`): no moves.
            } else {
                return Err(GcodeError {
                    line,
                    message: format!(
                        "`{}` is not a G-code command",
                        truncated(&cmd.to_ascii_uppercase())
                    ),
                });
            }
        }
        Ok((moves, start.unwrap_or(DVec3::ZERO)))
    }

    /// A line of G-code from a small vocabulary: moves with any of the axes, relative and
    /// absolute modes, G92, G28, line numbers, comments, checksums, a Klipper command, and
    /// now and then a word that is not a number or not a command.
    fn gcode_line() -> impl Strategy<Value = String> {
        prop_oneof![
            6 => (0u8..16, -50.0f64..50.0, -50.0f64..50.0, 0.0f64..9.0, -1.0f64..3.0).prop_map(|(axes, x, y, z, e)| {
                let mut l = String::from(if axes & 1 == 0 { "G1" } else { "g0" });
                for (bit, word) in [(1, format!(" X{x:.3}")), (2, format!(" Y{y:.3}")), (4, format!(" Z{z:.3}")), (8, format!(" E{e:.5}"))] {
                    if axes & bit != 0 || bit == 1 {
                        l.push_str(&word);
                    }
                }
                l
            }),
            1 => prop_oneof![Just("G90"), Just("G91"), Just("M82"), Just("M83"), Just("G28"), Just("G92 E0"), Just("G92 X1 Z2"), Just("N7 G1 X1 E1*42 ; numbered"), Just("; a comment"), Just(""), Just("SET_PRINT_STATS_INFO CURRENT_LAYER=3"), Just("M117 Xhello")].prop_map(String::from),
            // The writer's own form, and lines a hair away from it (the general reader's).
            4 => (-500.0f64..500.0, -500.0f64..500.0, 0.0f64..400.0, -2.0f64..2.0, 0u8..8).prop_map(|(x, y, z, e, var)| match var {
                0 => format!("G1 X{x:.3} Y{y:.3} Z{z:.3} E{e:.5}"),
                1 => format!("G1 X{x:.3} Y{y:.3} Z{z:.3} E{e:.5} F{:.1}", z * 10.0),
                2 => format!("G0 X{x:.3} Y{y:.3}"),
                3 => format!("G1 X{x:.3} Y{y:.3} X{z:.3} E{e:.5}"),
                4 => format!("G1 X{x:.3}  Y{y:.3} Z{z:.3} "),
                5 => format!("G1 X{x:.15} Y{y:.20} E{:.1}", e * 1e14),
                6 => format!("G1 X{x:.0}. Y.{:.0} Z-{z} E-", y.abs()),
                _ => format!("G1 X{x:.3} Y{y:.3};c F1"),
            }),
            1 => prop_oneof![Just("G1"), Just("G1 "), Just("G1 X"), Just("G1 X-"), Just("G1 X."), Just("G1 X1.2.3"), Just("G1 Q1"), Just("G1\tX1"), Just("G1 X1\rY2"), Just("G10 X1"), Just("G1 F"), Just("G1 Fx X2")].prop_map(String::from),
            1 => prop_oneof![Just("G1 Xhello"), Just("G92 Ebad"), Just("frobnicate"), Just("G20"), Just("G1 X1e400"), Just("G91\nG1 X1e308\nG1 X1e308")].prop_map(String::from),
        ]
    }

    /// A line a program's body may hold after its set-up: any line of [`gcode_line`] but the
    /// ones that change a mode (G90/G91, M82/M83, G92, G28), whose parts are resolved at the
    /// same time.
    fn body_line() -> impl Strategy<Value = String> {
        gcode_line().prop_filter("changes no mode", |l| {
            !["G9", "M8", "G28"].iter().any(|c| l.starts_with(c))
        })
    }

    /// `text` read whole, in parts, and fed to the reader in pieces read whole or in parts:
    /// each gives the moves, start and first error of the one-pass reader.
    fn reads_as_the_whole_file(text: &str, part_bytes: usize) -> Result<(), TestCaseError> {
        let reference = parse_moves_reference(text);
        prop_assert_eq!(parse_moves_in(text, usize::MAX), reference.clone());
        prop_assert_eq!(parse_moves_in(text, part_bytes), reference.clone());
        // Fed to the reader in pieces cut anywhere (in a line, in a CRLF, in a number).
        let mut reader = MoveReader::with_capacity(0);
        for piece in text.as_bytes().chunks(part_bytes) {
            reader.feed(piece);
        }
        prop_assert_eq!(reader.finish(), reference.clone());
        // And each piece read in parts of its own.
        let mut reader = MoveReader::with_capacity(0);
        reader.part_bytes = 1 + part_bytes / 7;
        for piece in text.as_bytes().chunks(part_bytes) {
            reader.feed(piece);
        }
        prop_assert_eq!(reader.finish(), reference);
        Ok(())
    }

    proptest! {
        /// Read in parts of any size (or whole), a file gives the moves, start and first error of
        /// the one-pass reader: the modal state (relative moves and E, G92, G28) carries across
        /// the cuts, and the line numbers and the error are the file's; so does the reader fed
        /// pieces cut anywhere, each read whole or in parts.
        #[test]
        fn parts_read_as_the_whole_file(lines in proptest::collection::vec(gcode_line(), 0..60), part_bytes in 1usize..200, crlf in any::<bool>()) {
            reads_as_the_whole_file(&lines.join(if crlf { "\r\n" } else { "\n" }), part_bytes)?;
        }

        /// The same for a set-up of any lines and then a body that changes no mode, whose parts
        /// are resolved at the same time, each from the state told from the parts before it:
        /// relative or absolute E, axes left out, errors in any part.
        #[test]
        fn parts_resolved_together_read_as_the_whole_file(setup in proptest::collection::vec(gcode_line(), 0..4), body in proptest::collection::vec(body_line(), 0..80), part_bytes in 1usize..300) {
            let lines: Vec<String> = setup.into_iter().chain(body).collect();
            reads_as_the_whole_file(&lines.join("\n"), part_bytes)?;
        }
    }

    #[test]
    fn a_reader_names_the_line_that_is_not_text() {
        let mut reader = MoveReader::with_capacity(0);
        reader.feed(b"G1 X1\nG1 X");
        reader.feed(b"2\n; caf\xc3");
        reader.feed(b"\xa9 ok\nG1 X\xff\nG1 X3\n");
        let e = reader.finish().unwrap_err();
        assert_eq!((e.line, e.message.as_str()), (4, "not text (UTF-8)"));
        let mut reader = MoveReader::with_capacity(0);
        reader.feed(b"G1 X1\nG1 X2 E1");
        let (moves, _) = reader.finish().unwrap();
        assert_eq!((moves.len(), moves[1].to.x, moves[1].de), (2, 2.0, 1.0));
    }

    /// A program written with its body's moves told (as `clayloft gcode` hands them to its
    /// self-check) reads as its text: the same moves, ends, E and lines, to the bit, on a
    /// corner-origin and centre-origin printer, Klipper's dialect, absolute E, with the hosts'
    /// layer and progress lines and without, over several rounds of the writer's pieces; and
    /// so does one whose pieces are streamed as they are formatted on both cores (each placed
    /// in the text at the offset the stream gives), its text the same byte for byte.
    #[test]
    fn a_body_told_by_its_writer_reads_as_its_text() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        /// The program's text and its reader: the body's pieces in rounds (`told` of them with
        /// their moves), or with `stream`, each as it is formatted through a sink.
        struct Recording {
            text: Vec<u8>,
            reader: MoveReader,
            told: usize,
            stream: bool,
        }
        impl crate::gcode::ProgramOut for Recording {
            fn text(&mut self, bytes: &[u8]) -> std::io::Result<()> {
                self.text.extend_from_slice(bytes);
                self.reader.feed(bytes);
                Ok(())
            }
            fn wants_moves(&self) -> bool {
                true
            }
            fn body(&mut self, pieces: &[ToldPiece<'_>]) -> std::io::Result<()> {
                for p in pieces {
                    self.text.extend_from_slice(p.text);
                    self.told += usize::from(p.moves.is_some());
                }
                self.reader.feed_told(pieces);
                Ok(())
            }
            fn with_sink(
                &mut self,
                moves: usize,
                body: &mut dyn FnMut(&dyn crate::gcode::PieceSink) -> std::io::Result<()>,
            ) -> Option<std::io::Result<()>> {
                struct Sink<'s, 'r> {
                    stream: &'s ToldStream<'r>,
                    text: &'s std::sync::Mutex<Vec<u8>>,
                    told: &'s AtomicUsize,
                }
                impl crate::gcode::PieceSink for Sink<'_, '_> {
                    fn take(&self, k: usize, piece: &ToldPiece<'_>) -> std::io::Result<()> {
                        self.told
                            .fetch_add(usize::from(piece.moves.is_some()), Ordering::Relaxed);
                        self.stream.take(k, piece, |at| {
                            let mut text = self.text.lock().unwrap();
                            let (at, end) = (at as usize, at as usize + piece.text.len());
                            let len = text.len().max(end);
                            text.resize(len, 0);
                            text[at..end].copy_from_slice(piece.text);
                        });
                        Ok(())
                    }
                    fn abandon(&self) {
                        self.stream.abandon();
                    }
                }
                if !self.stream {
                    return None;
                }
                let at = self.text.len() as u64;
                let text = std::sync::Mutex::new(std::mem::take(&mut self.text));
                let told = AtomicUsize::new(0);
                let mut outcome = Ok(());
                let end = self.reader.stream_told(at, moves, |stream| {
                    outcome = body(&Sink {
                        stream,
                        text: &text,
                        told: &told,
                    });
                });
                self.text = text.into_inner().unwrap();
                self.told += told.into_inner();
                assert_eq!(end, Some(self.text.len() as u64));
                Some(outcome)
            }
        }
        let bits = |m: &Move| (m.to.to_array().map(f64::to_bits), m.de.to_bits(), m.line);
        for printer in [
            "",
            "profile = \"klipper-paste-delta\"\n",
            "profile = \"wasp-2040-clay\"\nextrusion = \"absolute\"\n",
            "extrusion = \"absolute\"\nhost_metadata = false\nprogress = false\n",
            "host_metadata = true\nprogress = true\n",
        ] {
            let design = crate::load::parse_design(&format!(
                "version = 1\n[printer]\n{printer}[shape]\nheight = 120.0\nsamples = 480\nbase_layers = 1\n\
                 lower = {{ type = \"circle\", radius = 30.0 }}\nupper = {{ type = \"circle\", radius = 34.0 }}\n\
                 [texture.x]\nwave = \"sine\"\nperiod = 7\namplitude = 1.0\n"
            ))
            .unwrap();
            let job = crate::run(&design).unwrap();
            assert!(
                job.toolpath.points.len() > 3 * 16 * 1024,
                "several rounds of pieces"
            );
            let write = |stream: bool| {
                let mut out = Recording {
                    text: Vec::new(),
                    reader: MoveReader::with_capacity(0),
                    told: 0,
                    stream,
                };
                crate::gcode::write_program_to(&design, &job, &mut out).unwrap();
                assert!(out.told >= 3, "{printer}: the body's pieces are told");
                let (told, told_start) = out.reader.finish().unwrap();
                (out.text, told, told_start)
            };
            let (text, told, told_start) = write(false);
            let (read, read_start) = parse_moves(std::str::from_utf8(&text).unwrap()).unwrap();
            let (streamed_text, streamed, streamed_start) = write(true);
            assert!(streamed_text == text, "{printer}: streamed, the same text");
            for (moves, start) in [(told, told_start), (streamed, streamed_start)] {
                assert_eq!((moves.len(), start), (read.len(), read_start), "{printer}");
                for (t, r) in moves.iter().zip(&read) {
                    assert_eq!(bits(t), bits(r), "{printer}: line {}", r.line);
                }
            }
        }
    }

    /// Pieces taken by a stream, each on a thread of its own, started last piece first: the
    /// moves, lines and state of feeding the text in order, each piece's text placed after the
    /// text before it, with pieces not told (read here) and pieces that change a mode among
    /// them; and the first error where a piece has one.
    #[test]
    fn a_stream_of_pieces_reads_as_their_text() {
        let head = "G90\nM83\nG1 X0 Y2 Z0.5\n";
        let pieces = [
            (
                "G1 X1 Y2 Z0.5 E0.1\nM117 Layer 2\nG1 X2 Y2 Z0.5 E0.1\n",
                true,
            ),
            ("G91\nG1 X1 E0.1\nG90\n", false),
            ("G1 X3 Y2 Z1 E0.1\n", true),
            ("G92 E0\nG1 X4 Y2 Z1 E0.2\nM82\nG1 X5 E0.4\n", false),
            ("G1 X6 Y3 Z1 E0.5\n", true),
        ];
        let stream = |pieces: &[(&str, bool)]| {
            let text: String = std::iter::once(head)
                .chain(pieces.iter().map(|p| p.0))
                .collect();
            let mut reader = MoveReader::with_capacity(0);
            reader.feed(head.as_bytes());
            let raw: Vec<Part<'static>> = pieces.iter().map(|p| read_part(p.0)).collect();
            let count = raw.iter().map(|p| p.moves.len()).sum();
            let placed = std::sync::Mutex::new(Vec::new());
            let end = reader.stream_told(head.len() as u64, count, |s| {
                std::thread::scope(|scope| {
                    for (k, (piece, told)) in pieces.iter().enumerate().rev() {
                        let (raw, placed) = (&raw[k], &placed);
                        scope.spawn(move || {
                            let piece = ToldPiece {
                                text: piece.as_bytes(),
                                moves: told.then_some(&raw.moves[..]),
                                lines: piece.lines().count(),
                            };
                            s.take(k, &piece, |at| placed.lock().unwrap().push((k, at)));
                        });
                    }
                });
            });
            let mut placed = placed.into_inner().unwrap();
            placed.sort_unstable();
            (text, reader, end, placed)
        };
        let (text, reader, end, placed) = stream(&pieces);
        assert_eq!(end, Some(text.len() as u64));
        let mut at = head.len() as u64;
        for (k, (piece, _)) in pieces.iter().enumerate() {
            assert_eq!(placed[k], (k, at));
            at += piece.len() as u64;
        }
        let lines = reader.lines;
        assert_eq!(reader.finish(), parse_moves(&text));
        assert_eq!(lines, text.lines().count());
        // A piece that cannot be read: the first error, as reading the text gives it.
        let mut broken = pieces;
        broken[3].0 = "G1 X4 Y2 Z1 E0.2\nG1 X1e999\n";
        let (text, reader, _, _) = stream(&broken);
        let error = parse_moves(&text).expect_err("broken");
        assert_eq!(reader.finish().expect_err("broken"), error);
    }

    /// Pieces not told, or told while a cut line waits, are read as text: the same moves as
    /// feeding the text.
    #[test]
    fn pieces_not_told_are_read() {
        let text = "G90\nM83\nG1 X1 Y2 Z0.5 E0.1\nG1 X2 Y2 Z0.5 E0.1\nG1 X3 Y2 Z0.5 E0.1\n";
        let (want, _) = parse_moves(text).unwrap();
        let (head, body) = text.split_at(8);
        // Told moves that are wrong on purpose: taken only where they may be.
        let wrong = [Move {
            to: DVec3::splat(9.0),
            de: 9.0,
            line: 1,
        }];
        let mut not_told = MoveReader::with_capacity(0);
        not_told.feed(head.as_bytes());
        not_told.feed_told(&[ToldPiece {
            text: body.as_bytes(),
            moves: None,
            lines: 3,
        }]);
        assert_eq!(not_told.finish().unwrap().0, want);
        let mut cut = MoveReader::with_capacity(0);
        cut.feed(&head.as_bytes()[..5]);
        cut.feed(&head.as_bytes()[5..]);
        cut.feed(b"G1 X1 Y2");
        cut.feed_told(&[ToldPiece {
            text: &body.as_bytes()[8..],
            moves: Some(&wrong),
            lines: 3,
        }]);
        assert_eq!(cut.finish().unwrap().0, want);
    }

    #[test]
    fn one_pass_reading_keeps_the_words_rules() {
        // Lower case, a line number, a checksum, a comment; the first X of a line counts; F is
        // not read; relative moves and E; G92 resets E.
        let text = "g90\nN7 g1 x10 Y5 Z0.5 X99 F1200 e1*12 ; first\nM83\nG91\nG1 X1 E0.5\n\
                    G90\nM82\nG92 E0\nG1 X20 E2\nSET_VELOCITY_LIMIT VELOCITY=50\n";
        let (moves, start) = parse_moves(text).unwrap();
        assert_eq!(start, DVec3::ZERO);
        assert_eq!(moves.len(), 3);
        assert_eq!(moves[0].to, DVec3::new(10.0, 5.0, 0.5));
        assert_eq!((moves[0].de, moves[0].line), (1.0, 2));
        assert_eq!(moves[1].to, DVec3::new(11.0, 5.0, 0.5));
        assert_eq!(moves[1].de, 0.5);
        assert_eq!((moves[2].to.x, moves[2].de), (20.0, 2.0));
        // A bad number is named only where the command reads it.
        assert!(parse_moves("M117 Xhello\n").is_ok());
        let e = parse_moves("G1 X1\nG1 Xhello\n").unwrap_err();
        assert_eq!(
            (e.line, e.message.as_str()),
            (2, "`Xhello` is not a number")
        );
        let e = parse_moves("N3\nfrobnicate\n").unwrap_err();
        assert!(e.message.contains("FROBNICATE"), "{}", e.message);
    }
}
