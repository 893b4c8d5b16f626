//! Progress of a long run: a bar with frames per second and ETA on a terminal, plain lines
//! otherwise (logs, CI).

use std::io::IsTerminal;
use std::time::Instant;

pub struct Progress {
    bar: Option<indicatif::ProgressBar>,
    total: u64,
    done: u64,
    start: Instant,
    last_line: Instant,
}

impl Progress {
    pub fn new(total: u64, what: &str) -> Progress {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = indicatif::ProgressBar::new(total);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{msg} [{bar:30}] {pos}/{len} frames, {per_sec}, ETA {eta}",
                )
                .expect("valid template")
                .progress_chars("=> "),
            );
            bar.set_message(what.to_owned());
            bar
        });
        let now = Instant::now();
        Progress {
            bar,
            total,
            done: 0,
            start: now,
            last_line: now,
        }
    }

    pub fn frame_done(&mut self) {
        self.done += 1;
        match &self.bar {
            Some(bar) => bar.inc(1),
            None => {
                // Plain lines: at most one every 2 s, plus the last frame.
                if self.last_line.elapsed().as_secs_f64() >= 2.0 || self.done == self.total {
                    self.last_line = Instant::now();
                    let secs = self.start.elapsed().as_secs_f64();
                    let fps = self.done as f64 / secs.max(1e-9);
                    let eta = (self.total - self.done) as f64 / fps.max(1e-9);
                    eprintln!(
                        "frame {}/{} ({fps:.2} frames/s, ETA {eta:.0} s)",
                        self.done, self.total
                    );
                }
            }
        }
    }

    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
