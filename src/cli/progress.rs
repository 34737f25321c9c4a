//! Progress on stderr: a live line on a terminal, JSON lines elsewhere, none with `--quiet`.

use std::io::Write;

/// How progress goes to stderr.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum ProgressMode {
    Off,
    /// A live line "step done/total" on a terminal, redrawn at most every 100 ms.
    Line,
    /// Not a terminal: one JSON object a line, `{"progress": {"step", "done", "total"}}`, at most
    /// one a second, the first after a second (a quick run or refusal prints none).
    JsonLines,
}

/// The progress on stderr.
pub struct ProgressLine {
    mode: ProgressMode,
    started: std::time::Instant,
    last: Option<std::time::Instant>,
    drawn: bool,
}

impl ProgressLine {
    pub fn new(mode: ProgressMode) -> Self {
        Self { mode, started: std::time::Instant::now(), last: None, drawn: false }
    }

    /// Shows step `step` at `done` of `total` (0: open-ended).
    pub fn show(&mut self, step: &str, done: u32, total: u32) {
        let since = |t: Option<std::time::Instant>| t.map_or(u128::MAX, |t| t.elapsed().as_millis());
        match self.mode {
            ProgressMode::Off => return,
            ProgressMode::JsonLines => {
                if self.started.elapsed().as_millis() >= 1000 && since(self.last) >= 1000 {
                    self.last = Some(std::time::Instant::now());
                    eprintln!("{}", serde_json::json!({ "progress": { "step": step, "done": done, "total": total } }));
                }
                return;
            }
            ProgressMode::Line if since(self.last) < 100 => return,
            ProgressMode::Line => {}
        }
        self.last = Some(std::time::Instant::now());
        let text = if total > 0 { format!("{step} {done}/{total}") } else { step.to_string() };
        eprint!("\r{text:<60}");
        let _ = std::io::stderr().flush();
        self.drawn = true;
    }

    pub fn clear(&mut self) {
        if self.drawn {
            eprint!("\r{:<60}\r", "");
            self.drawn = false;
        }
    }
}
