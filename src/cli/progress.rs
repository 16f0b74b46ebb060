//! The progress line of `meshtrace render` on a terminal: the bar, the samples per pixel
//! done out of the total, the rate in human units, the elapsed time, and an ETA from the
//! throughput of the last few seconds (so that it converges once the render runs steadily,
//! whatever its first pass cost).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::VecDeque;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How far back the ETA's throughput looks.
const WINDOW: Duration = Duration::from_secs(3);

/// The line is redrawn at most this often.
const REDRAW: Duration = Duration::from_millis(200);

/// A render's progress, fed with finished samples from any thread.
pub struct Progress {
    bar: ProgressBar,
    pixels: u64,
    spp: u32,
    start: Instant,
    state: Mutex<State>,
}

struct State {
    done: u64,
    recent: Throughput,
    drawn: Option<Instant>,
}

/// A running count's rate over about the last [`WINDOW`]: what an ETA that converges needs,
/// whatever the first pass cost. The progress line and the preview window's statistics
/// read it.
pub struct Throughput {
    /// (time, count then), oldest first, spanning about [`WINDOW`].
    recent: VecDeque<(Instant, u64)>,
}

impl Throughput {
    /// A count of 0 at `start`.
    pub fn new(start: Instant) -> Self {
        Self {
            recent: VecDeque::from([(start, 0)]),
        }
    }

    /// Records that the count is `total` at `now` and returns its recent rate per second.
    pub fn record(&mut self, now: Instant, total: u64) -> f64 {
        self.recent.push_back((now, total));
        while self.recent.len() > 2 && now - self.recent[1].0 >= WINDOW {
            self.recent.pop_front();
        }
        let (t0, c0) = self.recent[0];
        total.saturating_sub(c0) as f64 / (now - t0).as_secs_f64().max(1e-9)
    }
}

impl Progress {
    /// The line for `width` x `height` pixels at `spp`; hidden with `quiet` or when standard
    /// error is not a terminal.
    pub fn new(width: u32, height: u32, spp: u32, quiet: bool) -> Self {
        let pixels = width as u64 * height as u64;
        let bar = if quiet || !std::io::stderr().is_terminal() {
            ProgressBar::hidden()
        } else {
            let bar = ProgressBar::with_draw_target(
                Some(pixels * spp as u64),
                ProgressDrawTarget::stderr(),
            );
            bar.set_style(
                ProgressStyle::with_template("{bar:30} {percent:>3}%  {msg}")
                    .expect("the template is valid"),
            );
            bar
        };
        let start = Instant::now();
        Self {
            bar,
            pixels,
            spp,
            start,
            state: Mutex::new(State {
                done: 0,
                recent: Throughput::new(start),
                drawn: None,
            }),
        }
    }

    /// Counts `samples` more finished samples (pixel samples, not samples per pixel).
    pub fn inc(&self, samples: u64) {
        let now = Instant::now();
        let Ok(mut st) = self.state.lock() else {
            return;
        };
        st.done += samples;
        let done = st.done;
        let recent_rate = st.recent.record(now, done);
        self.bar.set_position(done);
        if st.drawn.is_some_and(|t| now - t < REDRAW) {
            return;
        }
        st.drawn = Some(now);
        self.bar
            .set_message(self.line(done, now - self.start, recent_rate));
    }

    /// The message: e.g. `37.5/64 spp  0.72 Msamples/s  12s  ETA 9s`.
    fn line(&self, done: u64, elapsed: Duration, rate: f64) -> String {
        format!(
            "{}  {}  {}  ETA {}",
            spp_done(done, self.pixels, self.spp),
            human_rate(rate, "samples"),
            duration(elapsed.as_secs_f64()),
            eta(done, self.pixels * self.spp as u64, rate)
        )
    }

    /// Removes the line.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Samples per pixel done of the total, from `done` samples over `pixels`: `37.5/64 spp`.
pub fn spp_done(done: u64, pixels: u64, spp: u32) -> String {
    format!("{:.1}/{spp} spp", done as f64 / pixels.max(1) as f64)
}

/// The time left to reach `total` from `done` at `rate` per second: `9s`, or `?` at rate 0.
pub fn eta(done: u64, total: u64, rate: f64) -> String {
    if rate > 0.0 {
        duration(total.saturating_sub(done) as f64 / rate)
    } else {
        "?".into()
    }
}

/// `per_second` in k, M or G units: `0.72 Msamples/s`.
pub fn human_rate(per_second: f64, unit: &str) -> String {
    let (scale, prefix) = if per_second >= 1e9 {
        (1e9, "G")
    } else if per_second >= 1e5 {
        (1e6, "M")
    } else if per_second >= 1e2 {
        (1e3, "k")
    } else {
        (1.0, "")
    };
    let x = per_second / scale;
    let digits = if x >= 100.0 {
        0
    } else if x >= 10.0 {
        1
    } else {
        2
    };
    format!("{x:.digits$} {prefix}{unit}/s")
}

/// Seconds as `9s`, `3m05s` or `1h02m`.
pub fn duration(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    if s < 60 {
        format!("{s}s")
    } else if s < 3600 {
        format!("{}m{:02}s", s / 60, s % 60)
    } else {
        format!("{}h{:02}m", s / 3600, s % 3600 / 60)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_and_durations_read_as_people_write_them() {
        assert_eq!(human_rate(715_733.378_5, "samples"), "0.72 Msamples/s");
        assert_eq!(human_rate(12_345_678.0, "rays"), "12.3 Mrays/s");
        assert_eq!(human_rate(2.5e9, "rays"), "2.50 Grays/s");
        assert_eq!(human_rate(850.0, "samples"), "0.85 ksamples/s");
        assert_eq!(human_rate(12.0, "samples"), "12.0 samples/s");
        assert_eq!(duration(9.4), "9s");
        assert_eq!(duration(185.0), "3m05s");
        assert_eq!(duration(3720.0), "1h02m");
    }

    #[test]
    fn the_eta_follows_the_recent_rate() {
        let p = Progress::new(100, 100, 64, true);
        // 32 of 64 spp done at 1 Msamples/s recently: 320,000 samples left, 0.32 s.
        let line = p.line(320_000, Duration::from_secs(10), 1e6);
        assert_eq!(line, "32.0/64 spp  1.00 Msamples/s  10s  ETA 0s");
        let line = p.line(0, Duration::ZERO, 0.0);
        assert!(line.ends_with("ETA ?"), "{line}");
    }
}
