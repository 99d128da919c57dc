//! Print time along the toolpath: `t₀ = 0`, `tⱼ = tⱼ₋₁ + |pⱼ − pⱼ₋₁| / vⱼ` with vⱼ the speed of
//! the move into point j (mm/s), so the replay runs at the printer's pace.

use bevy::math::DVec3;
use clayloft_core::toolpath::Toolpath;

/// Cumulative print time at each toolpath point, s.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Timeline {
    times: Vec<f64>,
}

impl Timeline {
    pub fn new(path: &Toolpath) -> Timeline {
        let mut times = Vec::with_capacity(path.points.len());
        let mut t = 0.0;
        for (j, p) in path.points.iter().enumerate() {
            if j > 0 {
                t += path.points[j - 1].pos.distance(p.pos) / p.speed.max(1e-6);
            }
            times.push(t);
        }
        Timeline { times }
    }

    /// Whole print time, s.
    pub fn total_s(&self) -> f64 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// Print time when the nozzle reaches point `j`, s.
    pub fn time_of(&self, j: usize) -> f64 {
        self.times.get(j).copied().unwrap_or_else(|| self.total_s())
    }

    /// Index of the last point reached at time `t`.
    pub fn index_at(&self, t: f64) -> usize {
        self.times.partition_point(|x| *x <= t).saturating_sub(1)
    }

    /// Nozzle position at time `t`, between the points around it.
    pub fn position_at(&self, path: &Toolpath, t: f64) -> Option<DVec3> {
        let j = self.index_at(t);
        let a = path.points.get(j)?.pos;
        let Some(b) = path.points.get(j + 1) else {
            return Some(a);
        };
        let span = self.times[j + 1] - self.times[j];
        let f = if span > 0.0 {
            ((t - self.times[j]) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        Some(a.lerp(b.pos, f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clayloft_core::toolpath::PathPoint;

    #[test]
    fn time_follows_distance_over_speed() {
        let pt = |x: f64, speed: f64| PathPoint {
            pos: DVec3::new(x, 0.0, 1.0),
            thickness: 1.0,
            flow: 1.0,
            speed,
        };
        let path = Toolpath {
            points: vec![pt(0.0, 10.0), pt(10.0, 10.0), pt(30.0, 20.0)],
            base_points: 0,
            revolutions: 1,
            layer_starts: vec![0],
            findings: Vec::new(),
        };
        let tl = Timeline::new(&path);
        assert_eq!(tl.total_s(), 2.0);
        assert_eq!(tl.time_of(1), 1.0);
        assert_eq!(tl.index_at(0.5), 0);
        assert_eq!(tl.index_at(1.0), 1);
        assert_eq!(tl.index_at(99.0), 2);
        assert_eq!(tl.position_at(&path, 1.5), Some(DVec3::new(20.0, 0.0, 1.0)));
        assert_eq!(tl.position_at(&path, 0.25), Some(DVec3::new(2.5, 0.0, 1.0)));
    }
}
