//! Progress of long work on stderr: indicatif's bars on a terminal; in a log (stderr redirected
//! to a file or a pipe, a batch job) plain lines instead — what, how far, elapsed, the estimate
//! of what is left — at most one every [`LOG_INTERVAL`] per bar, with no escape codes.

use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle, TermLike};

/// The least time between two progress lines of one bar in a log.
pub const LOG_INTERVAL: Duration = Duration::from_secs(10);

/// Whether progress goes to a terminal (bars) or a log (lines).
pub fn to_terminal() -> bool {
    std::io::stderr().is_terminal()
}

/// A progress bar of `len` steps for work called `what`: on a terminal a bar with an estimate
/// of the time left (and the message set on it after); in a log a line such as "`what`: 120/540
/// (22 %), 1m elapsed, about 3m left".
pub fn progress_bar(len: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    if to_terminal() {
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{what:<28} {{bar:30}} {{pos}}/{{len}} eta {{eta}} {{msg}}"
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
    } else {
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{what}: {{pos}}/{{len}} ({{percent}} %), {{elapsed}} elapsed, about {{eta}} left {{msg}}"
            ))
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar.set_draw_target(ProgressDrawTarget::term_like_with_hz(Box::new(LogLines::default()), 1));
    }
    bar
}

/// A spinner for work of unknown length, showing the message set on it: on a terminal
/// indicatif's spinner, in a log the message as a line (at most one every [`LOG_INTERVAL`]).
pub fn spinner() -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    if !to_terminal() {
        bar.set_style(
            ProgressStyle::with_template("{msg}").unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        bar.set_draw_target(ProgressDrawTarget::term_like_with_hz(Box::new(LogLines::default()), 1));
    }
    bar
}

/// indicatif's drawing turned into log lines: each redraw is collected and written as one
/// line when [`LOG_INTERVAL`] has passed since the last one (or the work is complete); cursor
/// movements and clearing do nothing.
#[derive(Debug, Default)]
struct LogLines {
    state: Mutex<LogState>,
}

#[derive(Debug, Default)]
struct LogState {
    /// The redraw being collected.
    text: String,
    /// The last line written and when.
    last: Option<(Instant, String)>,
}

impl LogLines {
    fn add(&self, s: &str) {
        let mut state = self.state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        state.text.push_str(s);
    }
}

impl TermLike for LogLines {
    fn width(&self) -> u16 {
        200
    }
    fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn write_line(&self, s: &str) -> std::io::Result<()> {
        self.add(s);
        Ok(())
    }
    fn write_str(&self, s: &str) -> std::io::Result<()> {
        self.add(s);
        Ok(())
    }
    fn clear_line(&self) -> std::io::Result<()> {
        Ok(())
    }
    fn flush(&self) -> std::io::Result<()> {
        let mut state = self.state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let line = plain(std::mem::take(&mut state.text).trim());
        if line.is_empty() {
            return Ok(());
        }
        let due = match &state.last {
            None => true,
            Some((at, last)) => *last != line && (at.elapsed() >= LOG_INTERVAL || line.contains("(100 %)")),
        };
        if due {
            writeln!(std::io::stderr(), "{line}")?;
            state.last = Some((Instant::now(), line));
        }
        Ok(())
    }
}

/// `s` without ANSI escape sequences (ESC, `[`, parameters, a final letter).
fn plain(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            if chars.next() == Some('[') {
                for d in chars.by_ref() {
                    if d.is_ascii_alphabetic() {
                        break;
                    }
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escape_sequences_are_removed() {
        assert_eq!(plain("\u{1b}[1m\u{1b}[32msolves\u{1b}[0m: 3/10"), "solves: 3/10");
        assert_eq!(plain("no escapes, 100 %"), "no escapes, 100 %");
    }

    #[test]
    fn a_log_gets_a_line_at_first_then_only_after_the_interval_or_at_the_end() {
        let log = LogLines::default();
        let mut written = Vec::new();
        for text in ["a: 1/10 (10 %)", "a: 2/10 (20 %)", "a: 10/10 (100 %)", "a: 10/10 (100 %)"] {
            log.write_str(text).expect("collected");
            log.flush().expect("flushed");
            written.push(log.state.lock().expect("state").last.as_ref().map(|(_, l)| l.clone()));
        }
        let lines: Vec<_> = written.into_iter().flatten().collect();
        // The first redraw is written; the second falls inside the interval; the completed one
        // is written; repeating it is not.
        assert_eq!(lines, ["a: 1/10 (10 %)", "a: 1/10 (10 %)", "a: 10/10 (100 %)", "a: 10/10 (100 %)"]);
    }
}
