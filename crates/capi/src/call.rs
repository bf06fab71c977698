//! How every entry point runs: inside `catch_unwind`, its failure as a
//! status and the calling thread's one-line message, a handle checked and
//! poisoned by a panic.

use crate::types::*;
use deferred_msaa::Error;
use std::cell::RefCell;
use std::ffi::CString;
use std::panic::{AssertUnwindSafe, catch_unwind};

thread_local! {
    pub(crate) static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

/// What an entry point fails with: its status and message.
#[derive(Debug)]
pub(crate) struct Failure {
    pub(crate) status: DmsaaStatus,
    pub(crate) message: String,
}

impl Failure {
    pub(crate) fn new(status: DmsaaStatus, message: impl Into<String>) -> Self {
        Failure {
            status,
            message: message.into(),
        }
    }

    pub(crate) fn null(function: &str, argument: &str) -> Self {
        Failure::new(
            DmsaaStatus::NullPointer,
            format!("{function}: `{argument}` is null"),
        )
    }

    pub(crate) fn invalid(message: impl Into<String>) -> Self {
        Failure::new(DmsaaStatus::InvalidArgument, message)
    }

    /// The Rust error's message, under the status of its kind.
    pub(crate) fn from_error(error: &Error) -> Self {
        let status = match error {
            Error::InvalidArgument(_) => DmsaaStatus::InvalidArgument,
            Error::Retrofit { .. } | Error::Layout(_) => DmsaaStatus::UnsuitableFramebuffer,
            Error::Unsupported { .. }
            | Error::UnsupportedSampleCount { .. }
            | Error::UnsupportedFormat { .. } => DmsaaStatus::Unsupported,
            Error::MemoryBudget { .. } => DmsaaStatus::MemoryBudget,
            Error::SecondLighting(_) => DmsaaStatus::SecondLighting,
            Error::LayerMixUndeclared { .. } => DmsaaStatus::LayerMixUndeclared,
            Error::TwinsNotCleared { .. } => DmsaaStatus::TwinsNotCleared,
            Error::FrameNotBegun { .. } => DmsaaStatus::OutOfOrder,
            _ => DmsaaStatus::Gl,
        };
        Failure::new(status, error.to_string())
    }
}

impl From<Error> for Failure {
    fn from(error: Error) -> Self {
        Failure::from_error(&error)
    }
}

pub(crate) fn set_last_error(message: &str) {
    // An interior NUL cannot be given to C; it never occurs in the crate's
    // messages, but a driver log could hold one.
    let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = text);
}

/// Run one entry point's body: a panic becomes `DMSAA_STATUS_PANIC`, a
/// failure sets the thread's message.
pub(crate) fn entry(function: &str, body: impl FnOnce() -> Result<(), Failure>) -> DmsaaStatus {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => DmsaaStatus::Ok,
        Ok(Err(failure)) => {
            set_last_error(&failure.message);
            failure.status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "no message".into());
            set_last_error(&format!(
                "{function}: internal error (a panic: {}); please report it",
                what.lines().next().unwrap_or("")
            ));
            DmsaaStatus::Panic
        }
    }
}

/// The handle behind `retrofit`, checked: not null, not poisoned, not
/// destroyed. A panic while it is borrowed poisons it.
pub(crate) fn with_handle<T>(
    function: &str,
    retrofit: *mut DmsaaRetrofit,
    body: impl FnOnce(&mut DmsaaRetrofit) -> Result<T, Failure>,
) -> Result<T, Failure> {
    // SAFETY: the header requires a handle from `dmsaa_retrofit_new` not
    // yet destroyed, or null, which is refused here.
    let Some(handle) = (unsafe { retrofit.as_mut() }) else {
        return Err(Failure::null(function, "retrofit"));
    };
    if handle.poisoned {
        return Err(Failure::new(
            DmsaaStatus::Panic,
            format!(
                "{function}: this retrofit had an internal error earlier; destroy it and make a new one"
            ),
        ));
    }
    handle.poisoned = true;
    // The core's guards put the host's state back while a panic unwinds;
    // a GL error left on the way is drained before the panic goes on to
    // `entry`, so that none is left for the host.
    let result = match catch_unwind(AssertUnwindSafe(|| body(&mut *handle))) {
        Ok(result) => result,
        Err(payload) => {
            let _ = deferred_msaa::gl::check_error(handle.msaa.parts_mut().0, "a panic");
            std::panic::resume_unwind(payload)
        }
    };
    handle.poisoned = false;
    result
}
