//! Terminal text: lines that fit [`WIDTH`] columns and numbers without float
//! noise (`0.049999999999999996` prints as `0.05`).

/// Width every line of the command's own output fits in at most, columns.
pub const WIDTH: usize = 100;

/// Narrowest width the output is wrapped to, columns (a narrower terminal
/// wraps the lines itself).
pub const MIN_WIDTH: usize = 40;

/// The width to wrap to: the terminal's width where standard output or
/// standard error is a terminal (else `COLUMNS` where set), within
/// [`MIN_WIDTH`]..=[`WIDTH`]; [`WIDTH`] for pipes and files.
pub fn width() -> usize {
    let from_terminal = [libc::STDOUT_FILENO, libc::STDERR_FILENO]
        .into_iter()
        .find_map(terminal_columns);
    let columns = from_terminal.or_else(|| {
        std::env::var("COLUMNS")
            .ok()
            .and_then(|c| c.trim().parse::<usize>().ok())
    });
    columns.map_or(WIDTH, |c| c.clamp(MIN_WIDTH, WIDTH))
}

/// The column count of the terminal on `fd`, if it is one.
fn terminal_columns(fd: libc::c_int) -> Option<usize> {
    let mut ws = libc::winsize {
        ws_row: 0,
        ws_col: 0,
        ws_xpixel: 0,
        ws_ypixel: 0,
    };
    // SAFETY: TIOCGWINSZ writes one `winsize` into the struct we own; a
    // descriptor that is no terminal makes the call fail without writing.
    let r = unsafe { libc::ioctl(fd, libc::TIOCGWINSZ, &mut ws) };
    (r == 0 && ws.ws_col > 0).then_some(usize::from(ws.ws_col))
}

/// Significant digits a number keeps when [`tidy_numbers`] shortens it (the
/// library's one message format, [`beltune::error::short_number`]).
const TIDY_DIGITS: usize = beltune::error::SHORT_NUMBER_DIGITS;
/// Longest run of digits a number may print with: an integer of more digits
/// is beyond `u64` (not a count or a seed) and a fraction with more is mostly
/// zeros (`1e308` or `5e-324` printed in full).
const MAX_DIGIT_RUN: usize = 20;

/// Lay out `head` and `body` as one or more lines of at most `width` columns:
/// the head right-aligned in `head_width` columns and a colon, then the body;
/// continuation lines are indented to where the body started. The body breaks
/// after `, ` or `; ` outside brackets where possible (so that a quantity and
/// its unit stay together), else between words, never inside `[...]` (such as
/// `[axis busy 7.3 s]`); a single word longer than a line is kept whole.
pub fn wrap(head: &str, head_width: usize, body: &str, width: usize) -> Vec<String> {
    let first = format!("{head:>head_width$}: ");
    let indent = head_width + 2;
    let mut lines = Vec::new();
    let mut line = first;
    // Width of the body text already on the current line (0: nothing yet).
    let mut used = 0usize;
    let start_col = |line: &String| line.chars().count();
    for clause in clauses(body) {
        let clause_len = clause.chars().count();
        let col = start_col(&line);
        if used > 0 && col + 1 + clause_len.min(width) > width {
            lines.push(std::mem::take(&mut line).trim_end().to_string());
            line = " ".repeat(indent);
            used = 0;
        }
        if start_col(&line) + usize::from(used > 0) + clause_len <= width {
            if used > 0 {
                line.push(' ');
            }
            line.push_str(clause);
            used += clause_len;
            continue;
        }
        // The clause alone is too long for a line: break it between words.
        for word in words(clause) {
            let n = word.chars().count();
            if used > 0 && start_col(&line) + 1 + n > width {
                lines.push(std::mem::take(&mut line).trim_end().to_string());
                line = " ".repeat(indent);
                used = 0;
            }
            if used > 0 {
                line.push(' ');
            }
            line.push_str(word);
            used += n;
        }
    }
    lines.push(line.trim_end().to_string());
    lines
}

/// The body split after each `, ` and `; ` outside `(...)` and `[...]` (the
/// delimiter stays with the clause before it).
fn clauses(body: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut start = 0;
    let mut depth = 0i32;
    let bytes = body.as_bytes();
    for i in 0..bytes.len() {
        match bytes[i] {
            b'(' | b'[' => depth += 1,
            b')' | b']' => depth -= 1,
            b',' | b';' if depth <= 0 && bytes.get(i + 1) == Some(&b' ') => {
                out.push(body[start..=i].trim());
                start = i + 1;
            }
            _ => {}
        }
    }
    let rest = body[start..].trim();
    if !rest.is_empty() {
        out.push(rest);
    }
    out
}

/// The words of a clause: split at spaces, except inside `[...]`.
fn words(clause: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut start = 0;
    let mut depth = 0i32;
    for (i, b) in clause.bytes().enumerate() {
        match b {
            b'[' => depth += 1,
            b']' => depth -= 1,
            b' ' if depth <= 0 => {
                if i > start {
                    out.push(&clause[start..i]);
                }
                start = i + 1;
            }
            _ => {}
        }
    }
    if start < clause.len() {
        out.push(&clause[start..]);
    }
    out
}

/// A number for display: `v` rounded to 12 significant digits and printed in
/// its shortest form (`0.049999999999999996` -> `0.05`, `1e-7` stays `1e-7`).
pub fn tidy(v: f64) -> String {
    beltune::error::short_number(v)
}

/// `text` with every decimal number of more than 12 significant digits (the
/// full `f64` print of a value like `0.05 - 1e-17`) shortened by [`tidy`].
/// Integers and numbers already short are left as they are.
pub fn tidy_numbers(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < bytes.len() {
        let starts_number = bytes[i].is_ascii_digit()
            && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
        if !starts_number {
            let ch = text[i..].chars().next().unwrap_or(' ');
            out.push(ch);
            i += ch.len_utf8();
            continue;
        }
        let end = number_end(bytes, i);
        let token = &text[i..end];
        // Significant digits of the mantissa (leading zeros do not count).
        let digits = token
            .split(['e', 'E'])
            .next()
            .unwrap_or("")
            .trim_start_matches(['0', '.'])
            .bytes()
            .filter(u8::is_ascii_digit)
            .count();
        let run = token
            .split(['e', 'E'])
            .next()
            .unwrap_or("")
            .bytes()
            .filter(u8::is_ascii_digit)
            .count();
        match token.parse::<f64>() {
            Ok(v) if token.contains('.') && digits > TIDY_DIGITS => out.push_str(&tidy(v)),
            Ok(v) if run > MAX_DIGIT_RUN => out.push_str(&tidy(v)),
            _ => out.push_str(token),
        }
        i = end;
    }
    out
}

/// End of the number starting at `i`: digits, an optional fraction, an
/// optional exponent (only if digits follow it).
fn number_end(b: &[u8], mut i: usize) -> usize {
    let digits = |b: &[u8], mut i: usize| {
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    i = digits(b, i);
    if i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit() {
        i = digits(b, i + 1);
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut j = i + 1;
        if j < b.len() && (b[j] == b'-' || b[j] == b'+') {
            j += 1;
        }
        if j < b.len() && b[j].is_ascii_digit() {
            i = digits(b, j);
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn float_noise_is_rounded_away_and_short_numbers_stay() {
        assert_eq!(tidy(0.05 - 0.0), "0.05");
        assert_eq!(tidy(0.1 + 0.2), "0.3");
        assert_eq!(tidy(1e-7), "1e-7");
        assert_eq!(tidy(5.0), "5");
        assert_eq!(tidy(-2.5), "-2.5");
        assert_eq!(tidy(f64::NAN), "NaN");
        // The value of issue 16: 0.06 - 0.01 in f64.
        let noisy = 0.06_f64 - 0.01;
        assert_eq!(format!("{noisy}"), "0.049999999999999996");
        assert_eq!(tidy(noisy), "0.05");
        assert_eq!(
            tidy_numbers("`travel window [m]` = 0.049999999999999996: needs 50 mm"),
            "`travel window [m]` = 0.05: needs 50 mm"
        );
        assert_eq!(
            tidy_numbers("x 0.30000000000000004e-3 y"),
            "x 0.0003 y",
            "an exponent is part of the number"
        );
        // Far beyond any count or seed: the full print of 1e308 and 5e-324.
        assert_eq!(tidy_numbers(&format!("= {}: no", 1e308)), "= 1e308: no");
        assert_eq!(tidy_numbers(&format!("{} s", 5e-324)), "5e-324 s");
        assert_eq!(tidy_numbers(&format!("{} kg", -5e-324)), "-5e-324 kg");
        assert_eq!(tidy(-0.0), "0");
        // Left alone: integers, short decimals, digits inside words, versions.
        for s in [
            "seed 12345678901234567",
            "seed 18446744073709551615",
            "f_r 110.81 Hz",
            "sim-b2 v0.1.0",
            "egc70",
            "1.5e-3 N m",
            "run 3",
        ] {
            assert_eq!(tidy_numbers(s), s);
        }
    }

    #[test]
    fn wrapped_lines_fit_and_keep_every_word_in_order() {
        let body = "f_r 110.81 Hz, f_z 21.10 Hz, m_c 12.38 kg, c 217.5 kN/m, d_m 40.73 N s/m, \
                    d_c 185.75 N s/m, dead time 1.00 ms, fit 1.37 dB rms, coherence 0.992 \
                    [axis busy 7.3 s]";
        let lines = wrap("identification (open loop)", 28, body, 100);
        assert!(lines.len() > 1, "{lines:?}");
        for l in &lines {
            assert!(l.chars().count() <= 100, "{l}");
        }
        assert!(lines[0].starts_with("  identification (open loop): f_r 110.81 Hz,"));
        for l in &lines[1..] {
            assert!(
                l.starts_with(&" ".repeat(30)) && !l[30..].starts_with(' '),
                "{l:?}"
            );
        }
        // Breaks come after a comma (a quantity stays with its unit).
        for l in &lines[..lines.len() - 1] {
            assert!(l.ends_with(','), "{l:?}");
        }
        let words = |s: &str| s.split_whitespace().map(str::to_string).collect::<Vec<_>>();
        let joined: Vec<String> = lines
            .iter()
            .map(|l| l[30.min(l.len())..].to_string())
            .flat_map(|l| words(&l))
            .collect();
        let mut expected = vec![
            "identification".to_string(),
            "(open".into(),
            "loop):".into(),
        ];
        expected.extend(words(body));
        let mut got = words(&lines[0][..30]);
        got.extend(joined);
        assert_eq!(got, expected);
    }

    #[test]
    fn brackets_stay_whole_and_parentheses_keep_their_commas() {
        let body = "A_PRBS = 1.256 N m (+-0.628 N m around the holding torque) [axis busy 4.7 s]";
        let lines = wrap("excitation amplitude", 28, body, 100);
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert_eq!(lines[1].trim(), "[axis busy 4.7 s]");
        assert_eq!(
            clauses("a (b, c), d [e, f], g"),
            ["a (b, c),", "d [e, f],", "g"]
        );
        assert_eq!(words("x [a b] y"), ["x", "[a b]", "y"]);
    }

    #[test]
    fn a_short_line_stays_one_line_and_a_long_word_is_kept_whole() {
        assert_eq!(wrap("seed", 8, "1", 100), vec!["    seed: 1"]);
        let long = "x".repeat(120);
        let lines = wrap("file", 6, &format!("wrote {long}"), 100);
        assert_eq!(
            lines,
            vec!["  file: wrote".to_string(), format!("        {long}")]
        );
    }
}
