//! [`Later`]: a value made in the background after the server listens (the
//! stream, the tile hierarchy, the imagery's levels); until it is set,
//! routes that need it answer 503 with `Retry-After`.

use std::sync::{Arc, OnceLock};

/// A value being made, made, or failed.
#[derive(Debug)]
pub(crate) struct Later<T> {
    cell: OnceLock<std::result::Result<T, String>>,
    /// What it is, for messages ("the stream").
    what: &'static str,
}

/// Where a [`Later`] stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stage<'a, T> {
    /// Not made yet.
    Pending,
    /// Made.
    Ready(&'a T),
    /// Failed, with the reason.
    Failed(&'a str),
}

impl<T> Later<T> {
    /// Not made yet.
    pub(crate) fn pending(what: &'static str) -> Arc<Self> {
        Arc::new(Later {
            cell: OnceLock::new(),
            what,
        })
    }

    /// Made already.
    pub(crate) fn ready(what: &'static str, value: T) -> Arc<Self> {
        let l = Later {
            cell: OnceLock::new(),
            what,
        };
        let _ = l.cell.set(Ok(value));
        Arc::new(l)
    }

    /// Sets the outcome; false when it was set before (then ignored).
    pub(crate) fn set(&self, outcome: std::result::Result<T, String>) -> bool {
        self.cell.set(outcome).is_ok()
    }

    /// Where it stands.
    pub(crate) fn stage(&self) -> Stage<'_, T> {
        match self.cell.get() {
            None => Stage::Pending,
            Some(Ok(v)) => Stage::Ready(v),
            Some(Err(e)) => Stage::Failed(e),
        }
    }

    /// The value when made.
    pub(crate) fn get(&self) -> Option<&T> {
        match self.stage() {
            Stage::Ready(v) => Some(v),
            _ => None,
        }
    }

    /// What it is.
    pub(crate) fn what(&self) -> &'static str {
        self.what
    }

    /// A word for `/health`: `"ready"`, `"pending"` or `"failed"`.
    pub(crate) fn word(&self) -> &'static str {
        match self.stage() {
            Stage::Pending => "pending",
            Stage::Ready(_) => "ready",
            Stage::Failed(_) => "failed",
        }
    }
}
