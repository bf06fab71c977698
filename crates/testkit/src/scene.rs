//! Triangle soups as the toy [`Host`](crate::Host) draws them: interleaved
//! `[x, y, z, r, g, b]` view-space vertices.

use crate::Rng;

/// Append one triangle (view-space corners, one colour).
pub fn triangle(out: &mut Vec<f32>, corners: [[f32; 3]; 3], colour: [f32; 3]) {
    for c in corners {
        out.extend_from_slice(&c);
        out.extend_from_slice(&colour);
    }
}

/// The resolve benches' random scene: one far background triangle, then
/// `count` triangles 2 % to 25 % of the screen height across (log-uniform,
/// so most are small), 3 to 100 units away, a little tilted, in random order.
#[derive(Clone, Copy, Debug)]
pub struct RandomScene {
    /// Width over height of the image.
    pub aspect: f32,
    /// The vertical field of view, radians.
    pub fov_y: f32,
    /// How far away the background triangle is.
    pub background_z: f32,
    /// How many random triangles.
    pub count: usize,
    /// The generator's seed.
    pub seed: u64,
    /// Leave the top-right corner of the image empty, so that cleared
    /// samples are met too; else the background covers the whole view.
    pub open_corner: bool,
}

impl RandomScene {
    /// The vertices.
    pub fn vertices(&self) -> Vec<f32> {
        let mut rng = Rng::new(self.seed);
        let tan_half = (self.fov_y / 2.0).tan();
        let mut v = Vec::with_capacity((self.count + 1) * 18);
        let mut push = |p: [f32; 3], c: [f32; 3]| {
            v.extend_from_slice(&p);
            v.extend_from_slice(&c);
        };
        let (bx, by) = (
            self.background_z * tan_half * self.aspect,
            self.background_z * tan_half,
        );
        let corners = if self.open_corner {
            [[-1.5, -1.5], [1.6, -1.5], [-1.5, 1.6]]
        } else {
            [[-4.0, -2.0], [4.0, -2.0], [0.0, 4.0]]
        };
        for [x, y] in corners {
            push([x * bx, y * by, -self.background_z], [0.3, 0.4, 0.6]);
        }
        for _ in 0..self.count {
            let z = rng.range(3.0, 100.0);
            // Screen-space centre (NDC, a little beyond the edges) and size.
            let (cx, cy) = (rng.range(-1.1, 1.1), rng.range(-1.1, 1.1));
            let size = 0.02 * 12.5f32.powf(rng.unit()); // a fraction of the height
            let half_h = z * tan_half; // the view-space half height at distance z
            let radius = size * half_h; // circumradius, about half the size across
            let (ox, oy) = (cx * half_h * self.aspect, cy * half_h);
            let phase = rng.range(0.0, std::f32::consts::TAU);
            let color = [rng.unit(), rng.unit(), rng.unit()];
            for k in 0..3 {
                let a = phase + k as f32 * std::f32::consts::TAU / 3.0 + rng.range(-0.5, 0.5);
                let r = radius * rng.range(0.5, 1.0);
                let tilt = radius * rng.range(-0.3, 0.3);
                push([ox + r * a.cos(), oy + r * a.sin(), -(z + tilt)], color);
            }
        }
        v
    }
}
