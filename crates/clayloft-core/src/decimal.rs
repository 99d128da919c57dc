//! Decimal text of G-code numbers: fixed-point, rounded half away from zero, written three
//! digits (or two) at a time straight into the output's spare room ([`Line`]); and read back
//! ([`parse_f64`], [`decimal_prefix`]).
//!
//! A path point's line is about 40 bytes and five numbers; writing it word by word into the
//! output costs a capacity check and a copy call per word, and a division by a power of ten that
//! the compiler only turns into a multiplication when the power is known. [`Line`] knows it (the
//! decimals are a constant at every call) and writes into room reserved once a line.

use std::mem::MaybeUninit;

/// Two-digit pairs "00" … "99", for writing integers two digits per division.
const DIGIT_PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// The three digits of 0 … 999 as the low three bytes of a word, lowest first ("007" is
/// `b'0' | b'0' << 8 | b'7' << 16`): written into a line in one store.
const TRIPLES: [u32; 1000] = {
    let mut t = [0u32; 1000];
    let mut i = 0;
    while i < 1000 {
        t[i] = (b'0' + (i / 100) as u8) as u32
            | ((b'0' + (i / 10 % 10) as u8) as u32) << 8
            | ((b'0' + (i % 10) as u8) as u32) << 16;
        i += 1;
    }
    t
};

/// The digits of 0 … 999 without leading zeros, lowest first in the low three bytes, and
/// their count in the top byte ("7" is `b'7' | 1 << 24`): the whole part of a number in one load.
const WHOLES: [u32; 1000] = {
    let mut t = [0u32; 1000];
    let mut i = 0;
    while i < 1000 {
        let width = 1 + (i >= 10) as u32 + (i >= 100) as u32;
        t[i] = TRIPLES[i] >> (8 * (3 - width)) | width << 24;
        i += 1;
    }
    t
};

/// Most decimals a number is written with (`10^MAX_DECIMALS` fits the fast path's integers).
pub const MAX_DECIMALS: u32 = 6;

/// One line of text written straight into the spare room at the end of an output buffer
/// ([`Line::append`]), which holds any line of [`Line::CAPACITY`] bytes: five numbers of any
/// `f64` at up to [`MAX_DECIMALS`] decimals (at most 317 characters each, for `-1.8e308`) and
/// their words.
///
/// Written in place, a line is never read back: a line assembled on the stack and then copied
/// was read in wide loads from the narrow stores just made, which the processor cannot forward
/// and waits for (about half the writer's time here, sampled).
///
/// The room is [`Line::CAPACITY`] bytes and a word more, and a write goes to the line's length
/// taken modulo the capacity (a power of two): a word or a short constant written there lies
/// in the room whatever the length, so the compiler checks no bounds for it. A line never
/// reaches the capacity (tested with the longest numbers); one that did would panic in
/// [`Line::append`], never write outside the room.
pub struct Line<'a> {
    /// The output's room past its end; the first `len` bytes written.
    room: &'a mut [MaybeUninit<u8>; Line::ROOM],
    len: usize,
}

impl Line<'_> {
    pub const CAPACITY: usize = 2048;
    /// The capacity and the longest write of a constant length (a word, a G-code word's
    /// letters), which may start just below the capacity.
    const ROOM: usize = Self::CAPACITY + 8;

    /// Writes a line at the end of `out` with `write`, and gives what `write` gives.
    #[inline(always)]
    pub fn append<R>(out: &mut Vec<u8>, write: impl FnOnce(&mut Line<'_>) -> R) -> R {
        out.reserve(Self::ROOM);
        let room = (&mut out.spare_capacity_mut()[..Self::ROOM])
            .try_into()
            .expect("the room reserved");
        let mut line = Line { room, len: 0 };
        let result = write(&mut line);
        let len = line.len;
        assert!(len <= Self::CAPACITY, "a line of {len} bytes");
        // SAFETY: `len` is within the spare capacity, and every byte below it was written: each
        // write sets the bytes from `len` on before moving `len` past them (a word may set bytes
        // past its width, never fewer), and below the capacity the length modulo it is itself.
        unsafe { out.set_len(out.len() + len) };
        result
    }

    /// Where the next byte goes (see [`Line`]).
    #[inline(always)]
    fn at(&self) -> usize {
        self.len & (Self::CAPACITY - 1)
    }

    /// Appends `text` (panics past the room: a line is a few words).
    #[inline]
    pub fn text(&mut self, text: &[u8]) -> &mut Self {
        let at = self.at();
        self.room[at..at + text.len()].write_copy_of_slice(text);
        self.len += text.len();
        self
    }

    /// Appends `v` with exactly `decimals` digits after the point (none and no point for 0),
    /// rounded half away from zero; `-0` (and anything that rounds to it) is written `0`.
    /// `decimals` is at most [`MAX_DECIMALS`].
    #[inline]
    pub fn fixed(&mut self, v: f64, decimals: u32) -> &mut Self {
        self.fixed_with::<false>(v, decimals);
        self
    }

    /// [`Line::fixed`], giving the number its text reads as ([`decimal_prefix`]'s reading, to
    /// the bit: the digits n written are n / 10^decimals, one correctly rounded division, as the
    /// reader makes of them), or None where the number is not written as a plain decimal (not
    /// finite, or past the integers formatted here).
    #[inline]
    pub fn fixed_read(&mut self, v: f64, decimals: u32) -> Option<f64> {
        self.fixed_with::<true>(v, decimals)
    }

    /// [`Line::fixed`] (`READ` false) or [`Line::fixed_read`] (true): the decimals handed to the
    /// compiler as a constant.
    #[inline]
    fn fixed_with<const READ: bool>(&mut self, v: f64, decimals: u32) -> Option<f64> {
        match decimals {
            0 => self.fixed_const::<0, READ>(v),
            1 => self.fixed_const::<1, READ>(v),
            2 => self.fixed_const::<2, READ>(v),
            3 => self.fixed_const::<3, READ>(v),
            4 => self.fixed_const::<4, READ>(v),
            5 => self.fixed_const::<5, READ>(v),
            6 => self.fixed_const::<6, READ>(v),
            _ => panic!("at most {MAX_DECIMALS} decimals, not {decimals}"),
        }
    }

    /// [`Line::fixed_read`] with the decimals known to the compiler; the number read only with
    /// `READ` (else None: the writer of text alone pays no division).
    #[inline(always)]
    pub(crate) fn fixed_const<const D: u32, const READ: bool>(&mut self, v: f64) -> Option<f64> {
        let pow = 10u64.pow(D);
        let x = v.abs() * pow as f64;
        // Within range for integer formatting (false for too large, never for a real printer,
        // and for not a number; x is never negative).
        let in_range = x < 9.0e18;
        if !in_range {
            self.text(format!("{v:.*}", D as usize).as_bytes());
            return None;
        }
        // `x.round()` (half away from zero) without the library call the baseline x86-64 target
        // makes of it: below 2⁵³ the fraction `x − ⌊x⌋` is exact, above it x is whole.
        // Through i64 (x < 2⁶³): one conversion instruction each way.
        // SAFETY: x is a number from 0 to below 9e18, so its whole part fits an i64 (the
        // checked `as` would test for NaN and both ends again).
        let whole: i64 = unsafe { x.to_int_unchecked() };
        let n = (whole + i64::from(x - whole as f64 >= 0.5)) as u64;
        let negative = v < 0.0 && n != 0;
        if negative {
            self.text(b"-");
        }
        let int = n / pow;
        if int < 1000 {
            // One to three digits and their count from one entry.
            let entry = WHOLES[int as usize];
            self.word(entry & 0xff_ffff, (entry >> 24) as usize);
        } else {
            self.digits(int, int.checked_ilog10().map_or(1, |d| d as usize + 1));
        }
        let frac = n % pow;
        match D {
            0 => {}
            // The point and three digits in one word.
            3 => self.word(u32::from(b'.') | TRIPLES[frac as usize] << 8, 4),
            // The point and five: three, then a pair.
            5 => {
                self.word(u32::from(b'.') | TRIPLES[(frac / 100) as usize] << 8, 4);
                let pair = (frac % 100) as usize * 2;
                self.text(&DIGIT_PAIRS[pair..pair + 2]);
            }
            _ => {
                self.text(b".");
                self.digits(frac, D as usize);
            }
        }
        // The reader's fast path takes up to 19 digits below 2⁵³ (as the standard parser
        // would read more, it is left to it: None).
        if !READ || n >= 1 << 53 {
            return None;
        }
        let read = n as f64 / EXACT_POWERS[D as usize];
        Some(if negative { -read } else { read })
    }

    /// Appends the first `width` (at most 4) bytes of `word`, lowest first.
    #[inline]
    fn word(&mut self, word: u32, width: usize) {
        let at = self.at();
        self.room[at..at + 4].write_copy_of_slice(&word.to_le_bytes());
        self.len += width;
    }

    /// Appends the last `width` decimal digits of `n` (zero-padded).
    #[inline]
    fn digits(&mut self, mut n: u64, width: usize) {
        let at = self.at();
        let out = &mut self.room[at..at + width];
        let mut i = width;
        while i >= 2 {
            let pair = (n % 100) as usize * 2;
            n /= 100;
            i -= 2;
            out[i..i + 2].write_copy_of_slice(&DIGIT_PAIRS[pair..pair + 2]);
        }
        if i == 1 {
            out[0].write(b'0' + (n % 10) as u8);
        }
        self.len += width;
    }
}

/// Powers of ten that are exact in double precision.
pub(crate) const EXACT_POWERS: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// `text` as a number, exactly as `text.parse::<f64>()` reads it, reading the plain decimals a
/// G-code file is made of (`-12.345`, `7`, `.5`) itself ([`plain_decimal`]) and leaving anything
/// else to the standard library.
pub fn parse_f64(text: &str) -> Result<f64, std::num::ParseFloatError> {
    match plain_decimal(text.as_bytes()) {
        Some(v) => Ok(v),
        None => text.parse(),
    }
}

/// A plain decimal (an optional sign, digits with at most one point) read exactly as
/// `str::parse::<f64>` reads it; None for anything else, and for a decimal this fast path does
/// not take (more than 19 digits, or a mantissa from 2⁵³ on).
///
/// A plain decimal of m's digits with k after the point is m / 10^k. When m < 2⁵³ and k ≤ 22
/// both are exact doubles, and one division rounds the quotient correctly (IEEE 754), as the
/// standard parser does (Clinger's fast path): the same bits.
pub fn plain_decimal(bytes: &[u8]) -> Option<f64> {
    match decimal_prefix(bytes)? {
        (v, used) if used == bytes.len() => Some(v),
        _ => None,
    }
}

/// The plain decimal at the start of `bytes` (the longest run of an optional sign, digits and
/// at most one point) read as [`plain_decimal`] reads it, and the bytes it takes; None where
/// that would be None. For a reader that goes on after the number (a G-code word ends at a
/// space) without finding its end first.
pub fn decimal_prefix(bytes: &[u8]) -> Option<(f64, usize)> {
    let (negative, sign) = match bytes.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    // The digits before the point, then those after it: two short runs, each read by a loop
    // that only tests for a digit. More than 19 digits are left to the standard parser (the
    // mantissa is then wrong, and refused below).
    let run = |from: usize| {
        let (mut m, mut i) = (0u64, from);
        while let Some(d) = bytes
            .get(i)
            .map(|b| b.wrapping_sub(b'0'))
            .filter(|&d| d < 10)
        {
            m = m.wrapping_mul(10).wrapping_add(u64::from(d));
            i += 1;
        }
        (m, i)
    };
    let (whole, point) = run(sign);
    let (m, end, after_point) = if bytes.get(point) == Some(&b'.') {
        let (fraction, end) = run(point + 1);
        let after = end - point - 1;
        let m = whole
            .wrapping_mul(POWERS_OF_TEN[after.min(19)])
            .wrapping_add(fraction);
        (m, end, after)
    } else {
        (whole, point, 0)
    };
    let count = end - sign - usize::from(end > point);
    if count == 0 || count > 19 || m >= 1 << 53 || after_point >= EXACT_POWERS.len() {
        return None;
    }
    let v = m as f64 / EXACT_POWERS[after_point];
    Some((if negative { -v } else { v }, end))
}

/// 10⁰ … 10¹⁹ as integers.
const POWERS_OF_TEN: [u64; 20] = {
    let mut t = [1u64; 20];
    let mut i = 1;
    while i < 20 {
        t[i] = t[i - 1] * 10;
        i += 1;
    }
    t
};

/// `v` as a program writes it with `D` decimals and a reader reads it back
/// ([`Line::fixed_const`]: rounded half away from zero): what the checker of a written program
/// measures.
pub(crate) fn as_written<const D: u32>(v: f64) -> f64 {
    let x = v.abs() * 10u64.pow(D) as f64;
    // Not a number, or past the integers formatted: written by the formatter, as it is.
    if x.is_nan() || x >= 9.0e18 {
        return v;
    }
    let whole = x.trunc();
    let n = whole + if x - whole >= 0.5 { 1.0 } else { 0.0 };
    let read = n / EXACT_POWERS[D as usize];
    if v < 0.0 && n != 0.0 { -read } else { read }
}

/// Appends `v` with exactly `decimals` digits after the point to `buf` (see [`Line::fixed`]).
pub fn put_fixed(buf: &mut Vec<u8>, v: f64, decimals: u32) {
    Line::append(buf, |line| {
        line.fixed(v, decimals);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixed(v: f64, d: u32) -> String {
        let mut b = Vec::new();
        put_fixed(&mut b, v, d);
        String::from_utf8(b).unwrap()
    }

    /// A number as written with three decimals is what the program's text reads back as, to the
    /// bit: halves away from zero, a negative rounded to nothing written as 0.
    #[test]
    fn as_written_is_what_the_text_reads_back() {
        for v in [
            0.0,
            0.0005,
            1.0005,
            -2.0015,
            57.8205,
            140.794_499_9,
            -0.0004,
            123.456_789,
            -99.9995,
            1e-9,
            250.0,
        ] {
            let text = fixed(v, 3);
            assert_eq!(
                as_written::<3>(v).to_bits(),
                parse_f64(&text).unwrap().to_bits(),
                "{v}: {text}"
            );
        }
    }

    /// The text as the standard library's formatter writes it, rounded half away from zero with
    /// the library's `round` (the formatter itself rounds half to even): the reference.
    fn fixed_by_round(v: f64, decimals: u32) -> String {
        let pow = 10u64.pow(decimals);
        let scaled = (v.abs() * pow as f64).round();
        if !scaled.is_finite() || scaled >= 9.0e18 {
            return format!("{v:.*}", decimals as usize);
        }
        let n = scaled as u64;
        let sign = if v < 0.0 && n != 0 { "-" } else { "" };
        if decimals == 0 {
            format!("{sign}{}", n / pow)
        } else {
            format!("{sign}{}.{:0w$}", n / pow, n % pow, w = decimals as usize)
        }
    }

    proptest::proptest! {
        /// The same text as with the library's rounding, on any number: halves, whole numbers,
        /// values past 2⁵³ once scaled, the edge of the integer range, and the non-finite.
        #[test]
        fn fixed_point_rounds_as_the_library_does(
            v in proptest::num::f64::ANY,
            half in -1_000_000i64..1_000_000,
            d in 0u32..=MAX_DECIMALS,
        ) {
            for x in [v, half as f64 + 0.5, (half as f64 + 0.5) / 10f64.powi(d as i32), half as f64, 9.0e18 / 10f64.powi(d as i32), 4_503_599_627_370_497.0] {
                proptest::prop_assert_eq!(fixed(x, d), fixed_by_round(x, d), "{} with {} decimals", x, d);
            }
        }

        /// A line of five numbers is the numbers' texts one after another, whatever they are.
        #[test]
        fn a_line_is_its_words_in_order(vs in proptest::collection::vec(proptest::num::f64::ANY, 5)) {
            let mut out = Vec::new();
            let mut words = String::new();
            Line::append(&mut out, |line| {
                for (k, &v) in vs.iter().enumerate() {
                    let d = [3, 3, 3, 5, 1][k];
                    line.text(b" W").fixed(v, d);
                    words.push_str(" W");
                    words.push_str(&fixed_by_round(v, d));
                }
            });
            proptest::prop_assert_eq!(std::str::from_utf8(&out).unwrap(), words);
        }

        /// The number a text is told to read as is what the reader and the standard parser
        /// read, to the bit (zero's sign too), on any number, halves, and values near the
        /// limits; where none is told, the text is not a plain decimal the fast path reads.
        #[test]
        fn the_number_told_is_the_number_read(
            v in proptest::num::f64::ANY,
            small in -1.0e7f64..1.0e7,
            half in -1_000_000i64..1_000_000,
            d in 0u32..=MAX_DECIMALS,
        ) {
            let edge = 2f64.powi(53) / 10f64.powi(d as i32);
            for x in [v, small, -small * 1e-7, half as f64 + 0.5, (half as f64 + 0.5) / 10f64.powi(d as i32), edge, edge.next_down(), -0.0, 9.0e18] {
                let mut out = Vec::new();
                let told = Line::append(&mut out, |line| line.fixed_read(x, d));
                let text = std::str::from_utf8(&out).unwrap();
                let read = decimal_prefix(&out).filter(|&(_, used)| used == text.len());
                match told {
                    Some(t) => {
                        let (r, _) = read.expect("a plain decimal");
                        proptest::prop_assert_eq!(t.to_bits(), r.to_bits(), "{} with {} decimals: {}", x, d, text);
                        proptest::prop_assert_eq!(t.to_bits(), text.parse::<f64>().unwrap().to_bits());
                    }
                    None => proptest::prop_assert!(read.is_none(), "{} with {} decimals: {}", x, d, text),
                }
            }
        }
    }

    proptest::proptest! {
        /// The same number, or the same refusal, as the standard parser: plain decimals of any
        /// length (past 19 digits and 2⁵³), signs, lone points, exponents and other text.
        #[test]
        fn numbers_read_as_the_standard_parser_reads_them(
            text in "[+-]?[0-9]{0,24}(\\.[0-9]{0,24})?|[+-]?[0-9.eE+-]{0,12}|.{0,8}",
            v in proptest::num::f64::ANY,
            d in 0u32..=MAX_DECIMALS,
        ) {
            let written = fixed_by_round(v, d);
            for t in [text.as_str(), written.as_str()] {
                match (parse_f64(t), t.parse::<f64>()) {
                    (Ok(a), Ok(b)) => proptest::prop_assert_eq!(a.to_bits(), b.to_bits(), "{:?}", t),
                    (a, b) => proptest::prop_assert_eq!(a.is_ok(), b.is_ok(), "{:?}", t),
                }
                // Read as the start of a word (with more after it), a plain decimal is the same
                // number and ends where it ends; anything else stops short or is refused.
                let followed = format!("{t} Y1.5");
                match (plain_decimal(t.as_bytes()), decimal_prefix(followed.as_bytes())) {
                    (Some(a), Some((b, used))) => {
                        proptest::prop_assert_eq!((a.to_bits(), used), (b.to_bits(), t.len()), "{:?}", t)
                    }
                    (Some(_), None) => proptest::prop_assert!(false, "{:?} refused", t),
                    (None, prefix) => proptest::prop_assert!(prefix.is_none_or(|(_, used)| used < t.len()), "{:?}", t),
                }
            }
        }
    }

    #[test]
    fn fixed_formatting() {
        assert_eq!(fixed(12.3456, 3), "12.346");
        assert_eq!(fixed(0.0004, 3), "0.000");
        assert_eq!(fixed(-0.0004, 3), "0.000");
        assert_eq!(fixed(-1.5, 3), "-1.500");
        assert_eq!(fixed(0.05, 5), "0.05000");
        assert_eq!(fixed(3000.0, 0), "3000");
        assert_eq!(fixed(7.0, 1), "7.0");
        assert_eq!(fixed(1e300, 2).len(), format!("{:.2}", 1e300).len());
        assert_eq!(fixed(123456.789, 3), "123456.789");
        assert_eq!(fixed(0.00123, 5), "0.00123");
        assert_eq!(fixed(99.9996, 3), "100.000");
        for k in 0..2000 {
            let v = (k as f64 - 1000.0) * 0.7391;
            let written: f64 = fixed(v, 3).parse().unwrap();
            assert!((written - v).abs() <= 0.0005 + 1e-9, "{v} -> {written}");
        }
    }

    #[test]
    fn plain_decimals_read_back() {
        assert_eq!(parse_f64("-12.345"), Ok(-12.345));
        assert_eq!(parse_f64(".5"), Ok(0.5));
        assert_eq!(parse_f64("5."), Ok(5.0));
        assert_eq!(parse_f64("-0").map(f64::to_bits), Ok((-0.0f64).to_bits()));
        assert_eq!(parse_f64("9007199254740993"), Ok(9007199254740992.0));
        assert_eq!(parse_f64("1e3"), Ok(1000.0));
        assert!(parse_f64(".").is_err() && parse_f64("").is_err() && parse_f64("1.2.3").is_err());
    }

    /// A line appended gives its text and nothing more after what the output held, whether
    /// the output had room for it or grew, and the room past it is not the output's.
    #[test]
    fn a_line_appends_its_text_only() {
        let mut out = b"before;".to_vec();
        let mut want = out.clone();
        for len in [0, 1, 3, 4, 5, 37, 64, 300, Line::CAPACITY] {
            let text: Vec<u8> = (0..len).map(|k| b'a' + (k % 26) as u8).collect();
            Line::append(&mut out, |line| {
                line.text(&text);
            });
            want.extend_from_slice(&text);
            assert_eq!(out, want, "{len}");
            // Words of four bytes that keep fewer: only the kept bytes are the output's.
            Line::append(&mut out, |line| {
                line.word(u32::from_le_bytes(*b"WXYZ"), 1);
                line.word(u32::from_le_bytes(*b"wxyz"), 2);
            });
            want.extend_from_slice(b"Wwx");
            assert_eq!(out, want, "{len}");
        }
    }

    #[test]
    fn the_longest_line_fits() {
        let mut out = Vec::new();
        Line::append(&mut out, |line| {
            line.text(b"G1 X");
            for d in [3, 3, 3, MAX_DECIMALS, MAX_DECIMALS] {
                line.fixed(-f64::MAX, d).text(b" E");
            }
        });
        assert!(out.len() <= Line::CAPACITY);
        out.clear();
        Line::append(&mut out, |line| {
            line.fixed(-0.0, 3);
        });
        assert_eq!(out, b"0.000");
    }
}
