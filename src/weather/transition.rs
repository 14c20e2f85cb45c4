//! The weather timeline: a pure function of the requests and the host's time.
//!
//! A transition blends `from` toward `to` with a smoothstep weight over its duration. A request
//! that arrives while a transition runs freezes the current blend (scalars here, the weather map
//! baked on the GPU: Aetherius, "Presets and Transitions") and starts the new transition from
//! it, so nothing jumps however often the weather is changed.
//!
//! Time is the host's (seconds, f64). Within a transition, time may run backwards: times before
//! its start show its starting weather and the wind runs back. Requests must come in time order:
//! one earlier than the running transition's start is refused, because the states before an
//! interruption have been replaced by the baked one.

use glam::DVec2;

use super::preset::{Weather, Wind};
use crate::error::{Error, Result};

/// How far the wind has moved each texture since time 0, in meters along the tangent axes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WindOffsets {
    /// Weather map.
    pub weather: DVec2,
    /// Base-shape noise.
    pub base: DVec2,
    /// Detail noise.
    pub detail: DVec2,
}

/// The weather at one instant.
#[derive(Clone, Debug, PartialEq)]
pub struct WeatherSample {
    /// Every scalar blended.
    pub weather: Weather,
    /// Weight of the `to` weather map against the `from` one, in [0, 1].
    pub map_weight: f32,
    /// Wind displacement of each texture.
    pub offsets: WindOffsets,
}

/// What the GPU must do to the weather maps for a new request.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MapAction {
    /// The running transition had not started: the `from` map stays.
    KeepFrom,
    /// The running transition had finished: its `to` map becomes `from`.
    ToBecomesFrom,
    /// Interrupted half way: bake `mix(from, to, weight)` and make it `from`.
    Bake(f32),
}

/// Where the weather stands at a given time.
#[derive(Clone, Debug, PartialEq)]
pub struct TransitionState {
    /// Name of the weather the transition starts from (a frozen blend keeps the name of the
    /// nearer end).
    pub from: String,
    /// Name of the weather it heads to.
    pub to: String,
    /// Host time it starts at (s).
    pub start: f64,
    /// Its length (s); 0 for an instant change or a held sky.
    pub duration: f64,
    /// Blend weight in [0, 1] (smoothstep of the elapsed fraction).
    pub progress: f32,
    /// Scheduled (not begun), running, done, or pending (its map being generated).
    pub phase: TransitionPhase,
}

/// The phase of the transition at a given time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransitionPhase {
    /// It starts later.
    Scheduled,
    /// It is under way.
    Running,
    /// It has finished (or was instant): the sky holds its target.
    Done,
    /// Requested, its weather map still being generated over frames (`Renderer::set_weather`
    /// with a map larger than `Settings::weather_map_texels_per_frame`): it enters the
    /// timeline once the map is ready, at the later of its requested start and that frame's
    /// time. Never returned by a `Timeline` itself.
    Pending,
}

/// The transition state machine.
#[derive(Clone, Debug)]
pub struct Timeline {
    from: Weather,
    to: Weather,
    start: f64,
    duration: f64,
    offsets_at_start: WindOffsets,
}

/// Smoothstep weight of a transition at normalised time x (0 before, 1 after).
fn smooth(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// ∫₀ˣ smoothstep, extended with slope 0 before 0 and slope 1 after 1.
fn smooth_integral(x: f64) -> f64 {
    if x <= 0.0 {
        0.0
    } else if x < 1.0 {
        x * x * x - 0.5 * x * x * x * x
    } else {
        0.5 + (x - 1.0)
    }
}

fn velocities(w: &Wind) -> [DVec2; 3] {
    let v = w.direction.normalize_or_zero().as_dvec2() * w.speed as f64;
    [
        v * w.weather_factor as f64,
        v * w.base_factor as f64,
        v * w.detail_factor as f64,
    ]
}

impl Timeline {
    /// A timeline holding `weather` from time `start` on.
    pub fn new(weather: Weather, start: f64) -> Self {
        Self {
            from: weather.clone(),
            to: weather,
            start,
            duration: 0.0,
            offsets_at_start: WindOffsets::default(),
        }
    }

    /// Replaces the weather at once at time `at`, keeping the wind displacement continuous.
    pub fn replace(&mut self, weather: Weather, at: f64) {
        let offsets = self.offsets(at);
        *self = Timeline::new(weather, at);
        self.offsets_at_start = offsets;
    }

    /// Blend weight of the running transition at time `t`.
    pub fn weight(&self, t: f64) -> f32 {
        if self.duration <= 0.0 {
            return if t >= self.start { 1.0 } else { 0.0 };
        }
        smooth((t - self.start) / self.duration) as f32
    }

    /// The wind displacement at time `t`: the exact integral of the blended velocity.
    fn offsets(&self, t: f64) -> WindOffsets {
        let (vf, vt) = (velocities(&self.from.wind), velocities(&self.to.wind));
        let dt = t - self.start;
        let blended = if self.duration <= 0.0 {
            dt.max(0.0)
        } else {
            self.duration * smooth_integral(dt / self.duration)
        };
        let o = |i: usize, base: DVec2| base + vf[i] * dt + (vt[i] - vf[i]) * blended;
        WindOffsets {
            weather: o(0, self.offsets_at_start.weather),
            base: o(1, self.offsets_at_start.base),
            detail: o(2, self.offsets_at_start.detail),
        }
    }

    /// The weather at time `t`.
    pub fn sample(&self, t: f64) -> WeatherSample {
        let w = self.weight(t);
        WeatherSample {
            weather: Weather::lerp(&self.from, &self.to, w),
            map_weight: w,
            offsets: self.offsets(t),
        }
    }

    /// The weather the running transition heads to.
    pub fn target(&self) -> &Weather {
        &self.to
    }

    /// The transition as seen at time `t`.
    pub fn state(&self, t: f64) -> TransitionState {
        let phase = if t < self.start {
            TransitionPhase::Scheduled
        } else if t < self.start + self.duration {
            TransitionPhase::Running
        } else {
            TransitionPhase::Done
        };
        TransitionState {
            from: self.from.name.clone(),
            to: self.to.name.clone(),
            start: self.start,
            duration: self.duration,
            progress: self.weight(t),
            phase,
        }
    }

    /// Stops the weather where it is at time `now`: a running transition is frozen at its
    /// current blend, a scheduled one (starting after `now`) is dropped, and the sky holds
    /// from `now` on. Returns what must happen to the `from` map; the `to` map then becomes a
    /// copy of it. `now` may precede a scheduled transition's start, but not an earlier
    /// request's.
    pub fn hold(&mut self, now: f64) -> Result<MapAction> {
        if !now.is_finite() {
            return Err(Error::InvalidWeather(format!(
                "time must be finite, got {}",
                crate::validate::num(now)
            )));
        }
        let (action, held, offsets) = if now < self.start {
            // Not begun: its starting weather is what the sky shows until then.
            (MapAction::KeepFrom, self.from.clone(), self.offsets(now))
        } else {
            let sample = self.sample(now);
            let action = match sample.map_weight {
                w if w <= 0.0 => MapAction::KeepFrom,
                w if w >= 1.0 => MapAction::ToBecomesFrom,
                w => MapAction::Bake(w),
            };
            (action, sample.weather, sample.offsets)
        };
        self.from = held.clone();
        self.to = held;
        self.start = now;
        self.duration = 0.0;
        self.offsets_at_start = offsets;
        Ok(action)
    }

    /// Starts a transition to `target` at time `start` lasting `duration` seconds (0 = at
    /// once). Returns what must happen to the weather maps.
    pub fn request(&mut self, target: Weather, start: f64, duration: f64) -> Result<MapAction> {
        if !start.is_finite() {
            return Err(Error::InvalidWeather(format!(
                "start time must be finite, got {}",
                crate::validate::num(start)
            )));
        }
        if !(duration.is_finite() && duration >= 0.0) {
            return Err(Error::InvalidWeather(format!(
                "duration must be finite and >= 0, got {}",
                crate::validate::num(duration)
            )));
        }
        if start < self.start {
            return Err(Error::InvalidWeather(format!(
                "request at t={start} is earlier than the running transition's start t={}; \
                 requests must come in time order",
                self.start
            )));
        }
        target.validate()?;
        let now = self.sample(start);
        let action = match now.map_weight {
            w if w <= 0.0 => MapAction::KeepFrom,
            w if w >= 1.0 => MapAction::ToBecomesFrom,
            w => MapAction::Bake(w),
        };
        self.from = now.weather;
        self.to = target;
        self.start = start;
        self.duration = duration;
        self.offsets_at_start = now.offsets;
        Ok(action)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-6 * (1.0 + a.abs().max(b.abs()))
    }

    #[test]
    fn state_reports_phase_and_progress() {
        let mut t = Timeline::new(Weather::sparse(), 0.0);
        t.request(Weather::stormy(), 10.0, 20.0).unwrap();
        let s = t.state(5.0);
        assert_eq!(
            (s.phase, s.from.as_str(), s.to.as_str()),
            (TransitionPhase::Scheduled, "sparse", "stormy")
        );
        let s = t.state(20.0);
        assert_eq!(s.phase, TransitionPhase::Running);
        assert!((s.progress - 0.5).abs() < 1e-6);
        assert_eq!(t.state(31.0).phase, TransitionPhase::Done);
    }

    #[test]
    fn hold_freezes_a_running_transition_without_a_jump() {
        let mut t = Timeline::new(Weather::sparse(), 0.0);
        t.request(Weather::stormy(), 10.0, 20.0).unwrap();
        let before = t.sample(17.0);
        let action = t.hold(17.0).unwrap();
        assert!(matches!(action, MapAction::Bake(w) if (w - before.map_weight).abs() < 1e-6));
        // From now on the sky is what it was at 17 s, for ever; the wind goes on continuously.
        let after = t.sample(17.0);
        assert_eq!(after.weather, before.weather);
        assert!(close(after.offsets.base.x, before.offsets.base.x));
        assert_eq!(t.sample(500.0).weather, before.weather);
        assert_eq!(t.state(500.0).phase, TransitionPhase::Done);
    }

    #[test]
    fn hold_drops_a_scheduled_transition() {
        let mut t = Timeline::new(Weather::sparse(), 0.0);
        t.request(Weather::stormy(), 100.0, 20.0).unwrap();
        assert_eq!(t.hold(40.0).unwrap(), MapAction::KeepFrom);
        assert_eq!(t.sample(200.0).weather, Weather::sparse());
        assert!(t.hold(f64::NAN).is_err());
        // Requests go on from the hold.
        assert!(t.request(Weather::cloudy(), 30.0, 1.0).is_err());
        t.request(Weather::cloudy(), 41.0, 1.0).unwrap();
    }

    #[test]
    fn weights_follow_a_smoothstep() {
        let mut t = Timeline::new(Weather::sparse(), 0.0);
        t.request(Weather::stormy(), 10.0, 20.0).unwrap();
        assert_eq!(t.weight(5.0), 0.0);
        assert_eq!(t.weight(10.0), 0.0);
        assert!((t.weight(20.0) - 0.5).abs() < 1e-6);
        assert_eq!(t.weight(30.0), 1.0);
        assert_eq!(t.weight(1e9), 1.0);
        // Monotonic and continuous.
        let mut prev = 0.0;
        for k in 0..=200 {
            let w = t.weight(10.0 + k as f64 * 0.1);
            assert!(w >= prev && w - prev < 0.02);
            prev = w;
        }
        assert_eq!(t.sample(30.0).weather.clouds, Weather::stormy().clouds);
    }

    #[test]
    fn interruption_is_continuous() {
        let mut t = Timeline::new(Weather::cloudy(), 0.0);
        t.request(Weather::stormy(), 0.0, 60.0).unwrap();
        let before = t.sample(30.0);
        let action = t.request(Weather::clear(), 30.0, 40.0).unwrap();
        assert!(
            matches!(action, MapAction::Bake(w) if (w - 0.5).abs() < 1e-6),
            "{action:?}"
        );
        let after = t.sample(30.0);
        assert_eq!(before.weather, after.weather);
        assert_eq!(after.map_weight, 0.0, "the baked blend is the new start");
        assert_eq!(before.offsets, after.offsets);
        // Just after, the change is small: no jump in any scalar.
        let soon = t.sample(30.01);
        assert!((soon.weather.clouds.coverage - after.weather.clouds.coverage).abs() < 1e-4);
        for (a, b) in [
            (before.offsets.weather, soon.offsets.weather),
            (before.offsets.detail, soon.offsets.detail),
        ] {
            assert!((a - b).length() < 1.0, "{a} -> {b}");
        }
    }

    #[test]
    fn many_interruptions_in_a_row() {
        let mut t = Timeline::new(Weather::sparse(), 0.0);
        let presets = [
            Weather::stormy(),
            Weather::clear(),
            Weather::overcast(),
            Weather::cloudy(),
        ];
        let mut time = 0.0;
        for k in 0..40 {
            let before = t.sample(time);
            t.request(presets[k % 4].clone(), time, 10.0).unwrap();
            assert_eq!(before.weather, t.sample(time).weather, "request {k}");
            time += 3.7;
        }
        t.sample(time).weather.validate().unwrap();
    }

    #[test]
    fn replaying_the_same_requests_gives_the_same_sky() {
        let run = || {
            let mut t = Timeline::new(Weather::sparse(), 0.0);
            t.request(Weather::stormy(), 1.0, 10.0).unwrap();
            t.request(Weather::clear(), 4.5, 3.0).unwrap();
            t.request(Weather::overcast(), 6.0, 0.0).unwrap();
            t
        };
        let (a, b) = (run(), run());
        for time in [0.0, 5.0, 6.0, 7.5, 1000.0] {
            assert_eq!(a.sample(time), b.sample(time));
        }
        // Seeking: sampling out of order gives the same answers.
        assert_eq!(a.sample(1000.0), b.sample(1000.0));
        assert_eq!(a.sample(7.5), b.sample(7.5));
    }

    #[test]
    fn zero_and_huge_durations() {
        let mut t = Timeline::new(Weather::sparse(), 0.0);
        t.request(Weather::stormy(), 5.0, 0.0).unwrap();
        assert_eq!(t.weight(4.999), 0.0);
        assert_eq!(t.weight(5.0), 1.0);
        assert_eq!(
            t.request(Weather::clear(), 6.0, 1e30).unwrap(),
            MapAction::ToBecomesFrom
        );
        assert!(t.weight(1e6) < 1e-6);
        t.sample(1e12).weather.validate().unwrap();
        for bad in [f64::NAN, f64::INFINITY, -1.0] {
            assert!(matches!(
                t.request(Weather::clear(), 7.0, bad),
                Err(Error::InvalidWeather(_))
            ));
        }
    }

    #[test]
    fn time_going_backwards() {
        let mut t = Timeline::new(Weather::sparse(), 0.0);
        t.request(Weather::stormy(), 10.0, 10.0).unwrap();
        // Before the start: the starting weather, and the wind runs back linearly.
        assert_eq!(t.sample(2.0).weather, Weather::sparse());
        let v = velocities(&Weather::sparse().wind)[0];
        assert!(close(t.sample(2.0).offsets.weather.x, v.x * 2.0));
        // A request earlier than the running transition's start is refused; state unchanged.
        let e = t.request(Weather::clear(), 9.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("time order"), "{e}");
        assert_eq!(t.sample(20.0).weather.clouds, Weather::stormy().clouds);
    }

    #[test]
    fn wind_offset_is_the_integral_of_the_blended_velocity() {
        let mut slow = Weather::sparse();
        slow.wind.speed = 0.0;
        let mut fast = Weather::sparse();
        fast.wind.speed = 20.0;
        let mut t = Timeline::new(slow, 0.0);
        t.request(fast, 0.0, 10.0).unwrap();
        // Numerical integral of the blended velocity.
        let mut x = 0.0;
        let n = 100_000;
        for k in 0..n {
            let time = (k as f64 + 0.5) * 30.0 / n as f64;
            x += 20.0 * t.weight(time) as f64 * 30.0 / n as f64;
        }
        assert!((t.sample(30.0).offsets.weather.x - x).abs() < 1e-2, "{x}");
        // Detail moves twice as fast by default.
        assert!(close(
            t.sample(30.0).offsets.detail.x,
            2.0 * t.sample(30.0).offsets.weather.x
        ));
    }
}
