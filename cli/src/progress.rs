//! The terminal progress bar (indicatif) through which the `sdrs` verbs show
//! the core's [`sdrs::progress::Progress`] reports.

use indicatif::{ProgressBar, ProgressStyle};
use sdrs::progress::Progress;
use std::sync::OnceLock;

/// A progress bar on stderr drawn with an indicatif `template`; hidden with
/// `--quiet` and for operations of fewer than `min_len` units. With
/// `min_len` 0 the bar (a spinner until the length is known) shows at once.
pub struct Bar {
    template: &'static str,
    min_len: u64,
    quiet: bool,
    bar: OnceLock<ProgressBar>,
}

impl Bar {
    pub fn new(template: &'static str, min_len: u64, quiet: bool) -> Bar {
        let b = Bar {
            template,
            min_len,
            quiet,
            bar: OnceLock::new(),
        };
        if !quiet && min_len == 0 {
            let _ = b.bar.set(b.styled(0));
        }
        b
    }

    fn styled(&self, len: u64) -> ProgressBar {
        let p = ProgressBar::new(len);
        p.set_style(
            ProgressStyle::with_template(self.template)
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        p
    }
}

impl Progress for Bar {
    fn start(&self, len: u64, _what: &str) {
        if self.quiet || len < self.min_len {
            return;
        }
        self.bar.get_or_init(|| self.styled(len)).set_length(len);
    }

    fn message(&self, msg: &str) {
        if let Some(b) = self.bar.get() {
            b.set_message(msg.to_string());
        }
    }

    fn inc(&self) {
        if let Some(b) = self.bar.get() {
            b.inc(1);
        }
    }

    fn finish(&self) {
        if let Some(b) = self.bar.get() {
            b.finish_and_clear();
        }
    }
}
