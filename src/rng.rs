//! splitmix64: a tiny, fast, reproducible generator for jitter, synthetic scenes and tests
//! (not for anything that needs statistical quality beyond that).

#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    pub fn new(seed: u64) -> Self {
        let mut r = SplitMix64(seed);
        r.next_u64();
        r
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.uniform() as f32
    }

    /// A rotation from a normalised random quaternion (the models' unit tests; not
    /// uniform over the rotations, which they do not need).
    #[cfg(test)]
    pub(crate) fn rotation(&mut self) -> glam::DMat3 {
        let v = glam::DVec3::new(self.uniform(), self.uniform(), self.uniform()) - 0.5;
        let q = glam::DQuat::from_xyzw(v.x, v.y, v.z, self.uniform() - 0.5);
        glam::DMat3::from_quat(q.normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::SplitMix64;

    #[test]
    fn uniform_is_uniform_enough() {
        let mut r = SplitMix64::new(7);
        let mean: f64 = (0..10_000).map(|_| r.uniform()).sum::<f64>() / 10_000.0;
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
        assert!((0..1000).all(|_| (0.0..1.0).contains(&r.range(0.0, 1.0))));
    }
}
