//! Keyframed curves shared by camera paths, lights and moving colliders: a C¹ Hermite
//! spline through timed knots and a point with a value per keyframe.

use glam::Vec3;

/// A C1 cubic Hermite spline through (time, point) knots. Interior tangents are those of
/// Catmull-Rom generalised to non-uniform times: the derivative of the parabola through the
/// knot and its two neighbours; end tangents are the end secants (the curve is "extended"
/// linearly at its ends). Outside the knot range the end points hold.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Hermite {
    pub(crate) times: Vec<f32>,
    points: Vec<Vec3>,
    tangents: Vec<Vec3>,
}

impl Hermite {
    pub(crate) fn new(times: Vec<f32>, points: Vec<Vec3>) -> Hermite {
        let n = points.len();
        let secant = |i: usize| (points[i + 1] - points[i]) / (times[i + 1] - times[i]);
        let tangents = (0..n)
            .map(|i| {
                if n == 1 {
                    Vec3::ZERO
                } else if i == 0 {
                    secant(0)
                } else if i == n - 1 {
                    secant(n - 2)
                } else {
                    let (h0, h1) = (times[i] - times[i - 1], times[i + 1] - times[i]);
                    (secant(i - 1) * h1 + secant(i) * h0) / (h0 + h1)
                }
            })
            .collect();
        Hermite {
            times,
            points,
            tangents,
        }
    }

    pub(crate) fn eval(&self, seg: Segment) -> Vec3 {
        match seg {
            Segment::At(i) => self.points[i],
            Segment::Between(i, u) => {
                let h = self.times[i + 1] - self.times[i];
                let (u2, u3) = (u * u, u * u * u);
                let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
                let h10 = u3 - 2.0 * u2 + u;
                let h01 = -2.0 * u3 + 3.0 * u2;
                let h11 = u3 - u2;
                self.points[i] * h00
                    + self.tangents[i] * (h10 * h)
                    + self.points[i + 1] * h01
                    + self.tangents[i + 1] * (h11 * h)
            }
        }
    }

    /// d/dt of [`eval`](Self::eval) at `t` (in `seg`): the knot's tangent at a knot, 0 where
    /// the curve holds (before the first knot, at or after the last, a single knot).
    pub(crate) fn derivative(&self, seg: Segment, t: f32) -> Vec3 {
        let n = self.times.len();
        match seg {
            Segment::At(i)
                if (i == 0 && t < self.times[0]) || (i == n - 1 && t >= self.times[n - 1]) =>
            {
                Vec3::ZERO
            }
            Segment::At(i) => self.tangents[i],
            Segment::Between(i, u) => {
                let h = self.times[i + 1] - self.times[i];
                let u2 = u * u;
                // d/du of the Hermite basis, then du/dt = 1/h.
                let d00 = 6.0 * u2 - 6.0 * u;
                let d10 = 3.0 * u2 - 4.0 * u + 1.0;
                let d01 = -6.0 * u2 + 6.0 * u;
                let d11 = 3.0 * u2 - 2.0 * u;
                (self.points[i] * d00 + self.points[i + 1] * d01) / h
                    + self.tangents[i] * d10
                    + self.tangents[i + 1] * d11
            }
        }
    }
}

/// A point moving through timed keyframes on the same C¹ Hermite spline as camera
/// positions (lights use it), plus a linearly interpolated value per keyframe.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct KeyedPoint {
    spline: Hermite,
    values: Vec<Vec3>,
}

impl KeyedPoint {
    /// `times` strictly increasing, one point and one value per time.
    pub(crate) fn new(times: Vec<f32>, points: Vec<Vec3>, values: Vec<Vec3>) -> KeyedPoint {
        KeyedPoint {
            spline: Hermite::new(times, points),
            values,
        }
    }

    /// Position and value at `t` seconds (held before the first and after the last key).
    pub(crate) fn at(&self, t: f32) -> (Vec3, Vec3) {
        let seg = locate(&self.spline.times, t);
        let value = match seg {
            Segment::At(i) => self.values[i],
            Segment::Between(i, u) => self.values[i].lerp(self.values[i + 1], u),
        };
        (self.spline.eval(seg), value)
    }

    /// Time derivatives of [`at`](Self::at): the spline's velocity and the value's rate
    /// (piecewise constant; 0 where both hold, before the first and after the last key).
    pub(crate) fn rates_at(&self, t: f32) -> (Vec3, Vec3) {
        let times = &self.spline.times;
        let seg = locate(times, t);
        let rate = match seg {
            Segment::Between(i, _) => {
                (self.values[i + 1] - self.values[i]) / (times[i + 1] - times[i])
            }
            // At a knot inside the range: the rate of the segment that starts there.
            Segment::At(i) if i + 1 < times.len() && t >= times[0] => {
                (self.values[i + 1] - self.values[i]) / (times[i + 1] - times[i])
            }
            Segment::At(_) => Vec3::ZERO,
        };
        (self.spline.derivative(seg, t), rate)
    }
}

#[derive(Clone, Copy, Debug)]
pub(crate) enum Segment {
    /// Exactly at (or clamped to) knot i.
    At(usize),
    /// In (knot i, knot i + 1) at fraction u ∈ (0, 1).
    Between(usize, f32),
}

pub(crate) fn locate(times: &[f32], t: f32) -> Segment {
    let n = times.len();
    if n == 1 || t.is_nan() || t <= times[0] {
        return Segment::At(0);
    }
    if t >= times[n - 1] {
        return Segment::At(n - 1);
    }
    // First knot with time > t; t ≥ times[0] so i ≥ 1.
    let i = times.partition_point(|&k| k <= t) - 1;
    if t == times[i] {
        return Segment::At(i);
    }
    Segment::Between(i, (t - times[i]) / (times[i + 1] - times[i]))
}
