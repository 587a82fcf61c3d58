//! Running third-party readers that may panic on malformed input.
//!
//! [`quietly`] runs a closure under `catch_unwind` and turns a panic into an
//! error carrying the panic's message. While it runs, this thread's panics
//! are not printed: a process-wide panic hook, installed once, skips
//! printing for threads inside [`quietly`] and forwards every other panic
//! to the hook that was there before (so panics elsewhere still print as
//! usual).

use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Once;

thread_local! {
    static GUARDED: Cell<bool> = const { Cell::new(false) };
}

fn install_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !GUARDED.with(Cell::get) {
                previous(info);
            }
        }));
    });
}

/// Runs `f`; a panic inside it becomes `Err(message)`.
pub fn quietly<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    install_hook();
    let was = GUARDED.with(|g| g.replace(true));
    let out = catch_unwind(AssertUnwindSafe(f));
    GUARDED.with(|g| g.set(was));
    out.map_err(|payload| {
        payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "the reader panicked".to_string())
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_panic_becomes_an_error_and_values_pass_through() {
        assert_eq!(super::quietly(|| 3), Ok(3));
        let e = super::quietly(|| -> i32 { panic!("bad index {}", 7) }).unwrap_err();
        assert_eq!(e, "bad index 7");
    }
}
