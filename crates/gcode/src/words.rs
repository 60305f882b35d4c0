//! Splitting one G-code line into words (`X1.5`, `G2`, ...), dropping comments.

use crate::error::GcodeError;

/// One word of a block: a letter (upper case) and its number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Word {
    /// The letter, upper case.
    pub letter: char,
    /// The number as read.
    pub value: f64,
    /// 1-based column of the letter.
    pub col: usize,
}

/// What a line holds after comments are removed.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Line {
    /// Nothing to execute: blank, comment only, `%`, or a block-deleted line.
    Empty,
    /// The words in order.
    Words(Vec<Word>),
}

/// Splits `text` (one line, no newline) into words. `line` is the 1-based line number used in
/// errors; `block_delete` skips lines starting with `/`.
pub(crate) fn split_words(text: &str, line: usize, block_delete: bool) -> Result<Line, GcodeError> {
    // Sized once: a line has no more characters than bytes (collected, it grew by
    // reallocation, 18 M of the dome's ball verification's instructions).
    let mut chars: Vec<char> = Vec::with_capacity(text.len());
    chars.extend(text.chars());
    let err = |i: usize, m: String| GcodeError::new(line, i + 1, m);
    let mut i = 0;
    let skip_ws = |i: &mut usize| {
        while *i < chars.len() && chars[*i].is_whitespace() {
            *i += 1;
        }
    };
    skip_ws(&mut i);
    if i < chars.len() && chars[i] == '/' {
        if block_delete {
            return Ok(Line::Empty);
        }
        i += 1;
    }
    let mut words = Vec::with_capacity(8);
    let mut percent = false;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
        } else if c == '(' {
            let start = i;
            i += 1;
            loop {
                match chars.get(i) {
                    None => {
                        return Err(err(start, "comment '(' is not closed on this line".into()));
                    }
                    Some('(') => return Err(err(i, "nested '(' inside a comment".into())),
                    Some(')') => {
                        i += 1;
                        break;
                    }
                    Some(_) => i += 1,
                }
            }
        } else if c == ';' {
            break;
        } else if c == '%' {
            if !words.is_empty() || percent {
                return Err(err(i, "'%' must stand alone on its line".into()));
            }
            percent = true;
            i += 1;
        } else if c.is_ascii_alphabetic() {
            if percent {
                return Err(err(i, "'%' must stand alone on its line".into()));
            }
            let col = i;
            i += 1;
            skip_ws(&mut i);
            let (value, next) = number(&chars, i).ok_or_else(|| {
                err(
                    i,
                    format!("expected a number after '{}'", c.to_ascii_uppercase()),
                )
            })?;
            i = next;
            if let Some(&n) = chars.get(i)
                && !(n.is_whitespace() || n.is_ascii_alphabetic() || n == '(' || n == ';')
            {
                return Err(err(i, format!("malformed number: unexpected '{n}'")));
            }
            words.push(Word {
                letter: c.to_ascii_uppercase(),
                value,
                col: col + 1,
            });
        } else if c == '#' || c == '[' || c == '@' || c == '^' {
            return Err(err(
                i,
                format!("'{c}': parameters and expressions are not supported"),
            ));
        } else {
            return Err(err(i, format!("unexpected character '{c}'")));
        }
    }
    Ok(if words.is_empty() {
        Line::Empty
    } else {
        Line::Words(words)
    })
}

/// Reads `[+-]? (digits [. digits?] | . digits)` from `chars[i..]`; returns the value and the
/// index after it.
fn number(chars: &[char], mut i: usize) -> Option<(f64, usize)> {
    let start = i;
    if matches!(chars.get(i), Some('+' | '-')) {
        i += 1;
    }
    let mut digits = 0;
    while chars.get(i).is_some_and(|c| c.is_ascii_digit()) {
        i += 1;
        digits += 1;
    }
    if chars.get(i) == Some(&'.') {
        i += 1;
        while chars.get(i).is_some_and(|c| c.is_ascii_digit()) {
            i += 1;
            digits += 1;
        }
    }
    if digits == 0 {
        return None;
    }
    let s: String = chars[start..i].iter().collect();
    let v: f64 = s.parse().ok()?;
    v.is_finite().then_some((v, i))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_and_comments() {
        let Line::Words(w) = split_words("N10 g1 X-1.5 y .25 (c) Z+2. ; tail", 1, true).unwrap()
        else {
            panic!("no words")
        };
        let got: Vec<(char, f64, usize)> = w.iter().map(|w| (w.letter, w.value, w.col)).collect();
        assert_eq!(
            got,
            vec![
                ('N', 10.0, 1),
                ('G', 1.0, 5),
                ('X', -1.5, 8),
                ('Y', 0.25, 14),
                ('Z', 2.0, 24)
            ]
        );
        assert_eq!(split_words("  % ", 1, true).unwrap(), Line::Empty);
        assert_eq!(split_words("/G1 X1", 1, true).unwrap(), Line::Empty);
        assert!(matches!(
            split_words("/G1 X1", 1, false).unwrap(),
            Line::Words(_)
        ));
    }

    #[test]
    fn bad_numbers() {
        let e = split_words("G1 X1.2.3", 4, true).unwrap_err();
        assert_eq!((e.line, e.col), (4, 8));
        let e = split_words("G1 X", 2, true).unwrap_err();
        assert_eq!((e.line, e.col), (2, 5));
        let e = split_words("G1 (a (b))", 3, true).unwrap_err();
        assert_eq!((e.line, e.col), (3, 7));
        let e = split_words("G1 X#1", 3, true).unwrap_err();
        assert_eq!(e.col, 5);
    }
}
