//! Camera keyframes interpolated over time: Catmull-Rom on position and target (passing through
//! every key), linear on field of view; held constant before the first and after the last key.
//! A key with `cut` (or at the same time as the key before it) is a camera cut: the path is not
//! interpolated across it (the camera holds the previous key until the cut's time, then follows
//! the path from the cut key), and histories reset on the first frame after it.

use glam::{DMat4, DVec3};
use serde::Serialize;

#[derive(Clone, Debug, Serialize)]
pub struct CameraKey {
    pub time: f64,
    pub position: [f64; 3],
    pub target: [f64; 3],
    pub fov_y_deg: f64,
    /// The camera jumps to this key at its time (a camera cut).
    #[serde(default)]
    pub cut: bool,
}

/// The camera at one instant.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub position: DVec3,
    pub target: DVec3,
    pub fov_y_deg: f64,
    pub near: f64,
}

impl Camera {
    /// World-to-view (right-handed, looking down -Z, Y up), relative to the camera position: the
    /// renderer keeps world translation in f64 and feeds the GPU camera-relative coordinates.
    pub fn rotation(&self) -> DMat4 {
        let fwd = (self.target - self.position).normalize_or(DVec3::NEG_Z);
        let up = if fwd.cross(DVec3::Y).length_squared() < 1e-12 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let right = fwd.cross(up).normalize();
        let true_up = right.cross(fwd);
        // Rows are the camera axes: x = right, y = up, z = backwards.
        DMat4::from_mat3(glam::DMat3::from_cols(right, true_up, -fwd).transpose())
    }

    /// Reverse-Z, infinite far plane, Vulkan clip space (Y down): depth = near / view_z.
    pub fn projection(&self, aspect: f64) -> DMat4 {
        // clip = (f/aspect * x, -f * y, near, -z): NDC depth = near / -z (1 at the near plane, 0 at
        // infinity), NDC y points down as Vulkan's does.
        let f = 1.0 / (self.fov_y_deg.to_radians() * 0.5).tan();
        DMat4::from_cols(
            glam::DVec4::new(f / aspect, 0.0, 0.0, 0.0),
            glam::DVec4::new(0.0, -f, 0.0, 0.0),
            glam::DVec4::new(0.0, 0.0, 0.0, -1.0),
            glam::DVec4::new(0.0, 0.0, self.near, 0.0),
        )
    }
}

/// Why a vertical field of view (degrees) cannot make a picture: it must be finite and strictly
/// between 0 and 180 (at 180 the projection's focal length is 0, beyond it the image flips).
pub fn check_fov(fov_y_deg: f64) -> Result<(), String> {
    if fov_y_deg.is_finite() && fov_y_deg > 0.0 && fov_y_deg < 180.0 {
        Ok(())
    } else {
        Err(format!(
            "a vertical field of view of {fov_y_deg} degrees; give one between 0 and 180, exclusive"
        ))
    }
}

/// Why a point cannot be used: a coordinate that is not a finite number, or one beyond
/// [`crate::MAX_COORDINATE`] (f64 no longer holds it to a millimetre).
pub fn check_finite(point: [f64; 3]) -> Result<(), String> {
    point.into_iter().try_for_each(crate::check_coordinate)
}

/// Why a camera at `position` looking at `target` has no view direction: a non-finite coordinate,
/// or a target equal to the position.
pub fn check_direction(position: [f64; 3], target: [f64; 3]) -> Result<(), String> {
    check_finite(position)?;
    check_finite(target)?;
    let d = DVec3::from(target) - DVec3::from(position);
    if d == DVec3::ZERO {
        return Err(format!(
            "the target {target:?} is the camera's position: the camera looks nowhere"
        ));
    }
    if d.normalize_or_zero() == DVec3::ZERO {
        return Err(format!(
            "the target {target:?} and the position {position:?} give no direction (too close or too far apart)"
        ));
    }
    Ok(())
}

/// Why a near plane distance cannot be used: it must be finite and positive.
pub fn check_near(near: f64) -> Result<(), String> {
    if near.is_finite() && near > 0.0 {
        Ok(())
    } else {
        Err(format!("a near plane at {near}; give a positive distance"))
    }
}

impl CameraKey {
    /// Whether this key can make a picture (see [`check_fov`], [`check_direction`]).
    pub fn check(&self) -> Result<(), String> {
        if !self.time.is_finite() {
            return Err(format!("the time {} is not a finite number", self.time));
        }
        check_fov(self.fov_y_deg)?;
        check_direction(self.position, self.target)
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct CameraPath {
    pub keys: Vec<CameraKey>,
    pub near: f64,
}

fn catmull_rom(p0: DVec3, p1: DVec3, p2: DVec3, p3: DVec3, s: f64) -> DVec3 {
    let s2 = s * s;
    let s3 = s2 * s;
    0.5 * ((2.0 * p1)
        + (p2 - p0) * s
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * s2
        + (3.0 * p1 - p0 - 3.0 * p2 + p3) * s3)
}

impl CameraPath {
    /// Whether every key can make a picture and the near plane is usable; the error names the
    /// key by index.
    pub fn check(&self) -> Result<(), String> {
        if self.keys.is_empty() {
            return Err("the camera path has no keys".into());
        }
        check_near(self.near).map_err(|e| format!("camera: {e}"))?;
        for (i, k) in self.keys.iter().enumerate() {
            k.check().map_err(|e| format!("camera key {i}: {e}"))?;
        }
        Ok(())
    }

    /// Whether key `i` starts a new shot: flagged `cut`, or at the time of the key before it.
    fn is_cut(&self, i: usize) -> bool {
        i > 0 && (self.keys[i].cut || self.keys[i].time <= self.keys[i - 1].time)
    }

    /// Whether a camera cut falls in (t0, t1]: the frame at t1 does not continue the one at t0.
    pub fn cut_between(&self, t0: f64, t1: f64) -> bool {
        (1..self.keys.len())
            .any(|i| self.is_cut(i) && t0 < self.keys[i].time && self.keys[i].time <= t1)
    }

    pub fn at(&self, t: f64) -> Camera {
        // The shot containing t: from the last cut at or before t to the next cut.
        let n = self.keys.len();
        let start = (1..n)
            .rev()
            .find(|&i| self.is_cut(i) && self.keys[i].time <= t)
            .unwrap_or(0);
        let end = (start + 1..n).find(|&i| self.is_cut(i)).unwrap_or(n);
        self.at_in_shot(&self.keys[start..end], t)
    }

    fn at_in_shot(&self, k: &[CameraKey], t: f64) -> Camera {
        let cam = |i: usize| {
            (
                DVec3::from(k[i].position),
                DVec3::from(k[i].target),
                k[i].fov_y_deg,
            )
        };
        if k.len() == 1 || t <= k[0].time {
            let (position, target, fov_y_deg) = cam(0);
            return Camera {
                position,
                target,
                fov_y_deg,
                near: self.near,
            };
        }
        let last = k.len() - 1;
        if t >= k[last].time {
            let (position, target, fov_y_deg) = cam(last);
            return Camera {
                position,
                target,
                fov_y_deg,
                near: self.near,
            };
        }
        let i = k
            .iter()
            .rposition(|key| key.time <= t)
            .unwrap_or(0)
            .min(last - 1);
        let s = (t - k[i].time) / (k[i + 1].time - k[i].time).max(1e-12);
        let (a, b) = (i.saturating_sub(1), (i + 2).min(last));
        let pos = catmull_rom(cam(a).0, cam(i).0, cam(i + 1).0, cam(b).0, s);
        let tgt = catmull_rom(cam(a).1, cam(i).1, cam(i + 1).1, cam(b).1, s);
        let fov = cam(i).2 + (cam(i + 1).2 - cam(i).2) * s;
        Camera {
            position: pos,
            target: tgt,
            fov_y_deg: fov,
            near: self.near,
        }
    }

    /// A static camera framing the bounds (for a bare OBJ on the command line).
    pub fn framing(bounds: &crate::scene::Bounds, aspect: f64) -> CameraPath {
        let fov: f64 = 50.0;
        let r = bounds.radius().max(1e-3);
        // Fit the bounding sphere in the narrower field of view.
        let half = (fov.to_radians() * 0.5)
            .tan()
            .atan()
            .min((aspect * (fov.to_radians() * 0.5).tan()).atan());
        let dist = r / half.sin() * 1.05;
        let dir = DVec3::new(0.35, 0.3, 1.0).normalize();
        let c = bounds.center();
        CameraPath {
            keys: vec![CameraKey {
                time: 0.0,
                position: (c + dir * dist).to_array(),
                target: c.to_array(),
                fov_y_deg: fov,
                cut: false,
            }],
            near: (r * 0.002).max(1e-4),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(t: f64, x: f64) -> CameraKey {
        CameraKey {
            time: t,
            position: [x, 0.0, 0.0],
            target: [x, 0.0, -1.0],
            fov_y_deg: 40.0 + x,
            cut: false,
        }
    }

    #[test]
    fn cuts_jump_and_are_reported_once() {
        let mut keys = vec![key(0.0, 0.0), key(1.0, 2.0), key(2.0, 5.0), key(3.0, 6.0)];
        keys[2].cut = true;
        let p = CameraPath { keys, near: 0.1 };
        // Before the cut the camera holds the key before it; from the cut on it follows the new shot.
        assert!((p.at(1.5).position.x - 2.0).abs() < 1e-12);
        assert!((p.at(1.999).position.x - 2.0).abs() < 1e-12);
        assert!((p.at(2.0).position.x - 5.0).abs() < 1e-12);
        let mid = p.at(2.5).position.x;
        assert!(mid > 5.0 && mid < 6.0, "{mid}");
        assert!(p.cut_between(1.9, 2.0));
        assert!(!p.cut_between(2.0, 2.1));
        assert!(!p.cut_between(0.0, 1.9));
        // Two keys at one time: a cut without the flag.
        let q = CameraPath {
            keys: vec![key(0.0, 0.0), key(1.0, 1.0), key(1.0, 9.0)],
            near: 0.1,
        };
        assert!(q.cut_between(0.5, 1.0));
        assert!((q.at(1.0).position.x - 9.0).abs() < 1e-12);
        assert!((q.at(0.999).position.x - 1.0).abs() < 0.01);
    }

    #[test]
    fn passes_through_keys_and_holds_at_the_ends() {
        let p = CameraPath {
            keys: vec![key(0.0, 0.0), key(1.0, 2.0), key(2.0, 3.0)],
            near: 0.1,
        };
        assert!((p.at(1.0).position.x - 2.0).abs() < 1e-12);
        assert!((p.at(-5.0).position.x - 0.0).abs() < 1e-12);
        assert!((p.at(9.0).position.x - 3.0).abs() < 1e-12);
        assert!((p.at(0.5).fov_y_deg - 41.0).abs() < 1e-12);
        let mid = p.at(0.5).position.x;
        assert!(mid > 0.0 && mid < 2.0, "{mid}");
    }

    #[test]
    fn degenerate_cameras_are_refused() {
        let path = |k: CameraKey| CameraPath {
            keys: vec![key(0.0, 0.0), k],
            near: 0.1,
        };
        assert!(path(key(1.0, 1.0)).check().is_ok());
        for fov in [180.0, 0.0, -30.0, 200.0, f64::NAN, f64::INFINITY] {
            let err = path(CameraKey {
                fov_y_deg: fov,
                ..key(1.0, 1.0)
            })
            .check()
            .expect_err("bad field of view");
            assert!(
                err.starts_with("camera key 1: a vertical field of view of"),
                "{err}"
            );
        }
        assert!(check_fov(179.9).is_ok() && check_fov(0.1).is_ok());
        let err = path(CameraKey {
            target: [1.0, 0.0, 0.0],
            ..key(1.0, 1.0)
        })
        .check()
        .expect_err("looks nowhere");
        assert!(
            err.contains("camera key 1: the target") && err.contains("looks nowhere"),
            "{err}"
        );
        let err = path(CameraKey {
            position: [f64::NAN, 0.0, 0.0],
            ..key(1.0, 1.0)
        })
        .check()
        .expect_err("NaN");
        assert!(err.contains("NaN is not a finite number"), "{err}");
        for near in [0.0, -1.0, f64::INFINITY] {
            let mut p = path(key(1.0, 1.0));
            p.near = near;
            assert!(
                p.check()
                    .expect_err("near")
                    .starts_with("camera: a near plane")
            );
        }
    }

    #[test]
    fn projection_is_reverse_z_with_y_down() {
        let cam = Camera {
            position: DVec3::ZERO,
            target: DVec3::NEG_Z,
            fov_y_deg: 90.0,
            near: 0.5,
        };
        let p = cam.projection(1.0) * cam.rotation();
        let clip = p * glam::DVec4::new(0.0, 1.0, -2.0, 1.0);
        let ndc = clip.truncate() / clip.w;
        assert!((ndc.z - 0.25).abs() < 1e-12, "depth = near / z = 0.5 / 2");
        assert!(
            (ndc.y + 0.5).abs() < 1e-12,
            "up in the world is up on screen (negative NDC y)"
        );
    }
}
