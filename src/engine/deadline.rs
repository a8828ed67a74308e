//! When the caller stops waiting. The engine checks it between stages, between SLIC
//! iterations and between walks, and gives up with [`EngineError::DeadlineExceeded`],
//! so that a request past its deadline frees its worker within one iteration or walk.

use std::time::Instant;

use super::EngineError;

/// An instant after which the work is abandoned, or none.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Deadline(pub Option<Instant>);

impl Deadline {
    /// No deadline: the work always runs to its end.
    pub const NONE: Self = Self(None);

    /// `Err` once the deadline has passed.
    pub fn check(self) -> Result<(), EngineError> {
        match self.0 {
            Some(at) if Instant::now() >= at => Err(EngineError::DeadlineExceeded),
            _ => Ok(()),
        }
    }
}
