//! How a command ends: its exit codes, a failure with its message and code, and the verdict of a
//! method's run (a miss exits with 3 after its files are written).

use spherical_faces::export::Report;

pub(crate) const EXIT_CODES: &str = "Exit codes: 0 done; 1 the output could not be written; 2 bad arguments, bad input, or a \
refusal (the surface does not suit the method); 3 the files are written but the result misses a guarantee of its method \
(report.json: meets_guarantees false, with each guarantee's figure). Errors are one line on stderr, or one JSON object \
{\"error\": ..., \"exit_code\": ...} with --json.";

/// Why a command failed: the message and the exit code.
pub(crate) struct Failure {
    pub message: String,
    pub code: u8,
}

impl Failure {
    pub fn input(message: impl Into<String>) -> Self {
        Self { message: message.into(), code: 2 }
    }

    pub fn output(message: impl Into<String>) -> Self {
        Self { message: message.into(), code: 1 }
    }

    /// The files are written, but the result misses a guarantee of its method: the misses, for
    /// stderr.
    pub fn missed(report: &Report) -> Self {
        Self {
            message: format!("the result misses its guarantees: {}", report.failure_text()),
            code: spherical_faces::guarantees::MISSED_GUARANTEES_EXIT_CODE,
        }
    }
}

impl<E: std::fmt::Display> From<E> for Failure {
    fn from(e: E) -> Self {
        Failure::input(e.to_string())
    }
}

/// The summary when the report meets its guarantees; else the summary (what was written) goes
/// to stdout at once and the failure, with exit code 3, to stderr.
pub(crate) fn verdict(summary: String, report: &Report) -> Result<String, Failure> {
    if report.meets_guarantees == Some(true) {
        return Ok(summary);
    }
    println!("{summary}");
    Err(Failure::missed(report))
}
