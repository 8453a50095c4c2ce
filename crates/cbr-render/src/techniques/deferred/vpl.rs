//! The host side of `deferred`'s many lights, no Vulkan: where the sun's reflective shadow map
//! looks (an orthographic frame around the scene), which RSM texels become VPLs (a seeded
//! low-discrepancy pattern), and the random point lights of `points=N`. All deterministic per
//! scene seed.

use cbr_scene::rng::SplitMix;
use cbr_scene::{Bounds, PointLight, Scene};
use glam::{DMat4, DVec3, DVec4};

use crate::gpu_types::LightData;

/// Seed streams: the VPL pattern and the point lights draw from different SplitMix sequences of
/// the same scene seed.
const VPL_STREAM: u64 = 0x5650_4c73_0000_0001;
const POINTS_STREAM: u64 = 0x504f_494e_5453_0002;

/// The radical inverse of `i` in `base` (van der Corput): the Halton sequence's coordinates.
pub fn radical_inverse(base: u32, mut i: u32) -> f64 {
    let b = f64::from(base);
    let (mut inv, mut f) = (0.0, 1.0 / b);
    while i > 0 {
        inv += f64::from(i % base) * f;
        i /= base;
        f /= b;
    }
    inv
}

/// The RSM texels of `count` VPLs on a `side` x `side` map: the Halton (2, 3) points 1..=count,
/// shifted by a toroidal offset drawn from `seed` (a Cranley-Patterson rotation, which keeps
/// their low discrepancy), each taken to the texel it falls in.
pub fn vpl_texels(seed: u64, count: u32, side: u32) -> Vec<[u32; 2]> {
    let mut rng = SplitMix(seed ^ VPL_STREAM);
    let offset = [rng.next_f64(), rng.next_f64()];
    let s = f64::from(side);
    let texel = |x: f64| ((x * s) as u32).min(side - 1);
    (1..=count)
        .map(|i| {
            let u = (radical_inverse(2, i) + offset[0]).fract();
            let v = (radical_inverse(3, i) + offset[1]).fract();
            [texel(u), texel(v)]
        })
        .collect()
}

/// Where the sun's reflective shadow map looks this frame.
#[derive(Clone, Copy, Debug)]
pub struct SunView {
    /// Camera-relative world -> the RSM's clip space: x, y in [-1, 1] across a square of side
    /// `2 radius` around the framed region's bounding sphere, depth 1 on the sun's side of the
    /// sphere and 0 on the far side (reverse-Z, like the camera's).
    pub clip_from_world: DMat4,
    /// The sun's unit direction of travel.
    pub direction: DVec3,
    /// The map covers (2 radius)^2 square metres across the beam.
    pub radius: f64,
}

impl SunView {
    /// The `side` x `side` RSM around `region` (world), for a camera at `camera` (world), along
    /// `direction`. The map's centre is snapped to its texel grid in the sun's frame (world-
    /// anchored), so a still region keeps its texels whatever the camera does; the radius is the
    /// region's bounding sphere's, grown by the snap's largest shift.
    pub fn new(
        direction: [f32; 3],
        region: Bounds,
        camera: DVec3,
        side: u32,
    ) -> std::result::Result<SunView, String> {
        let d = DVec3::new(
            f64::from(direction[0]),
            f64::from(direction[1]),
            f64::from(direction[2]),
        )
        .normalize_or_zero();
        if d == DVec3::ZERO {
            return Err(format!(
                "the sun's direction {direction:?} is no direction: no reflective shadow map"
            ));
        }
        let up = if d.y.abs() < 0.99 { DVec3::Y } else { DVec3::X };
        let right = d.cross(up).normalize();
        let up = right.cross(d);
        // A single point still gets a map, 1 mm across.
        let radius = region.radius().max(1e-3) / (1.0 - 1.5 / f64::from(side));
        let texel = 2.0 * radius / f64::from(side);
        let c = region.center();
        let snap = |axis: DVec3| (c.dot(axis) / texel).round() * texel - c.dot(axis);
        let centre = c + right * snap(right) + up * snap(up) - camera;
        let row = |axis: DVec3, scale: f64, add: f64| {
            DVec4::new(axis.x * scale, axis.y * scale, axis.z * scale, add)
        };
        let rows = [
            row(right, 1.0 / radius, -centre.dot(right) / radius),
            row(up, 1.0 / radius, -centre.dot(up) / radius),
            row(d, -0.5 / radius, 0.5 + 0.5 * centre.dot(d) / radius),
            DVec4::new(0.0, 0.0, 0.0, 1.0),
        ];
        Ok(SunView {
            clip_from_world: DMat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose(),
            direction: d,
            radius,
        })
    }

    /// One texel's area across the beam on a `side` x `side` map (square metres).
    pub fn texel_area(&self, side: u32) -> f64 {
        let t = 2.0 * self.radius / f64::from(side);
        t * t
    }
}

/// The region the sun's map frames: the scene's bounds clipped to the cube of half-side `reach`
/// around the camera (VPLs far from everything the camera sees would light nothing visible);
/// `None` when nothing of the scene is within reach.
pub fn framed_region(scene: Bounds, camera: DVec3, reach: f64) -> Option<Bounds> {
    let min = scene.min.max(camera - reach);
    let max = scene.max.min(camera + reach);
    (min.cmple(max).all()).then_some(Bounds { min, max })
}

/// Each object's bounds in its own coordinates (before its origin and motion); `None` for an
/// object without vertices.
pub fn local_bounds(scene: &Scene) -> Vec<Option<(DVec3, DVec3)>> {
    scene
        .objects
        .iter()
        .map(|o| {
            let mut it = o.vertices.iter().map(|v| DVec3::from(v.pos.map(f64::from)));
            let first = it.next()?;
            Some(it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
        })
        .collect()
}

/// The scene's world bounds at time `t`: every object's local box through its transform then
/// (origin and motion), so moving objects stay inside the map.
pub fn bounds_at(scene: &Scene, local: &[Option<(DVec3, DVec3)>], t: f64) -> Bounds {
    let mut min = DVec3::splat(f64::INFINITY);
    let mut max = DVec3::splat(f64::NEG_INFINITY);
    for (i, b) in local.iter().enumerate() {
        let Some((lo, hi)) = b else { continue };
        let m = scene.object_transform(i, t);
        for k in 0..8 {
            let c = DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let p = m.transform_point3(c);
            min = min.min(p);
            max = max.max(p);
        }
    }
    if !min.is_finite() || !max.is_finite() {
        return Bounds {
            min: DVec3::ZERO,
            max: DVec3::ZERO,
        };
    }
    Bounds { min, max }
}

/// The centre of the box around the camera path's key positions.
fn path_centre(scene: &Scene) -> DVec3 {
    let (lo, hi) = key_box(scene);
    if lo.cmple(hi).all() {
        (lo + hi) * 0.5
    } else {
        scene.bounds().center()
    }
}

/// The box around the camera path's key positions (empty: min > max, without keys).
fn key_box(scene: &Scene) -> (DVec3, DVec3) {
    scene
        .camera
        .keys
        .iter()
        .map(|k| DVec3::from(k.position))
        .fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(p), hi.max(p)),
        )
}

/// Where `points=N` puts its lights: the scene's bounds within `reach` of the camera path's keys
/// (the box around every key position, grown by `reach`), or the whole bounds when nothing is
/// within reach. Fixed for the whole path, so the lights do not move with the camera.
pub fn points_region(scene: &Scene, reach: f64) -> Bounds {
    let b = scene.bounds();
    let (lo, hi) = key_box(scene);
    let (min, max) = (b.min.max(lo - reach), b.max.min(hi + reach));
    if min.cmple(max).all() {
        Bounds { min, max }
    } else {
        b
    }
}

/// `points=N`'s lights, deterministic per scene seed: each hovers over a random point of the
/// scene's surfaces inside [`points_region`] (uniform by area over every triangle clipped to the
/// region, at time 0), on the side that faces the camera path's centre, at 2% to 12% of its range; range an eighth of the
/// region's bounding radius; random saturated hue; intensity range^2 / count, so that the lights
/// together are about as bright whatever `count`. With no surface in the region they fill it
/// uniformly.
pub fn random_point_lights(scene: &Scene, count: u32, reach: f64) -> Vec<PointLight> {
    let region = points_region(scene, reach);
    let viewer = path_centre(scene);
    let range = (region.radius() * 0.125).max(1e-3);
    let intensity = (range * range) as f32 / count.max(1) as f32;
    let tris = surface_in(scene, region);
    let total = tris.last().map_or(0.0, |t| t.0);
    let mut rng = SplitMix(scene.settings.seed ^ POINTS_STREAM);
    (0..count)
        .map(|_| {
            let position = if total > 0.0 {
                let pick = rng.next_f64() * total;
                let k = tris.partition_point(|t| t.0 < pick).min(tris.len() - 1);
                let [a, b, c] = tris[k].1;
                let (r1, r2) = (rng.next_f64().sqrt(), rng.next_f64());
                let p = a * (1.0 - r1) + b * (r1 * (1.0 - r2)) + c * (r1 * r2);
                let n = (b - a).cross(c - a).normalize();
                let n = if n.dot(viewer - p) < 0.0 { -n } else { n };
                p + n * (range * (0.02 + 0.1 * rng.next_f64()))
            } else {
                let u = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
                region.min + (region.max - region.min) * u
            };
            PointLight {
                position: position.to_array(),
                color: rng.hue(),
                intensity,
                range: range as f32,
            }
        })
        .collect()
}

/// The scene's surface inside `region` at time 0: every triangle clipped to the box, as fans of
/// triangles with their cumulative area (for area-uniform sampling).
fn surface_in(scene: &Scene, region: Bounds) -> Vec<(f64, [DVec3; 3])> {
    let mut out = Vec::new();
    let mut total = 0.0;
    for (i, o) in scene.objects.iter().enumerate() {
        let m = scene.object_transform(i, 0.0);
        let world = |k: u32| {
            let v = o.vertices[k as usize].pos.map(f64::from);
            m.transform_point3(DVec3::from(v))
        };
        for t in o.indices.chunks_exact(3) {
            let poly = clip_to_box(vec![world(t[0]), world(t[1]), world(t[2])], region);
            for k in 2..poly.len() {
                let c = [poly[0], poly[k - 1], poly[k]];
                let area = 0.5 * (c[1] - c[0]).cross(c[2] - c[0]).length();
                if area > 0.0 && area.is_finite() {
                    total += area;
                    out.push((total, c));
                }
            }
        }
    }
    out
}

/// A convex polygon clipped to a box (Sutherland-Hodgman, one plane at a time).
fn clip_to_box(mut poly: Vec<DVec3>, b: Bounds) -> Vec<DVec3> {
    for axis in 0..3 {
        for (sign, bound) in [(1.0, b.min[axis]), (-1.0, b.max[axis])] {
            let f = |p: DVec3| sign * (p[axis] - bound);
            let mut next = Vec::with_capacity(poly.len() + 1);
            for (k, &p) in poly.iter().enumerate() {
                let q = poly[(k + 1) % poly.len()];
                let (fp, fq) = (f(p), f(q));
                if fp >= 0.0 {
                    next.push(p);
                }
                if (fp >= 0.0) != (fq >= 0.0) {
                    next.push(p + (q - p) * (fp / (fp - fq)));
                }
            }
            poly = next;
            if poly.is_empty() {
                return poly;
            }
        }
    }
    poly
}

/// Point lights as the shaders read them, camera-relative (the conversion of
/// crate::gpu_scene::GpuScene::update, so the same light gives the same bits).
pub fn light_data(points: &[PointLight], camera: DVec3) -> Vec<LightData> {
    points
        .iter()
        .map(|p| {
            let rel = (DVec3::from(p.position) - camera).as_vec3();
            let c = p.color.map(|c| c * p.intensity);
            LightData {
                position: [rel.x, rel.y, rel.z, 1.0],
                color: [c[0], c[1], c[2], p.range],
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radical_inverse_is_van_der_corput() {
        assert_eq!(radical_inverse(2, 1), 0.5);
        assert_eq!(radical_inverse(2, 6), 0.375);
        assert!((radical_inverse(3, 5) - (2.0 / 3.0 + 1.0 / 9.0)).abs() < 1e-15);
    }

    #[test]
    fn the_pattern_is_seeded_and_stratified() {
        let a = vpl_texels(7, 1024, 512);
        assert_eq!(a, vpl_texels(7, 1024, 512));
        assert_ne!(a, vpl_texels(8, 1024, 512));
        // Low discrepancy: 1024 points in 16 x 16 cells, 4 per cell on average. Uniform random
        // points would leave about 5 cells empty (Poisson: 256 e^-4) and a sum of squared
        // deviations from 4 of about 1024 (256 x the variance 4); the pattern leaves none empty
        // and less than half that sum (264 for seed 7).
        let mut cells = [0i32; 256];
        for [x, y] in &a {
            cells[(y / 32 * 16 + x / 32) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| c > 0), "{cells:?}");
        let squares: i32 = cells.iter().map(|c| (c - 4) * (c - 4)).sum();
        assert!(squares < 512, "{squares}: {cells:?}");
        assert!(a.iter().all(|t| t[0] < 512 && t[1] < 512));
    }

    #[test]
    fn the_sun_view_frames_the_bounds() {
        let b = Bounds {
            min: DVec3::new(-3.0, 0.0, -2.0),
            max: DVec3::new(5.0, 4.0, 1.0),
        };
        let cam = DVec3::new(10.0, 2.0, 7.0);
        let v = SunView::new([-0.3, -1.0, -0.5], b, cam, 64).expect("a direction");
        for k in 0..8 {
            let c = DVec3::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            let q = v.clip_from_world.transform_point3(c - cam);
            assert!(q.x.abs() <= 1.0 && q.y.abs() <= 1.0, "{q}");
            assert!((0.0..=1.0).contains(&q.z), "{q}");
        }
        // Nearer the sun is larger (reverse-Z).
        let centre = b.center() - cam;
        let near = v.clip_from_world.transform_point3(centre - v.direction);
        let far = v.clip_from_world.transform_point3(centre + v.direction);
        assert!(near.z > far.z);
        assert!(SunView::new([0.0; 3], b, cam, 64).is_err());
        // The texel grid is anchored in the world: another camera, the same texel centres.
        let other = DVec3::new(-40.0, 3.0, 1.5);
        let w = SunView::new([-0.3, -1.0, -0.5], b, other, 64).expect("a direction");
        let p = DVec3::new(0.7, 1.1, -0.4);
        let (a, c) = (
            v.clip_from_world.transform_point3(p - cam),
            w.clip_from_world.transform_point3(p - other),
        );
        assert!((a - c).length() < 1e-12, "{a} vs {c}");
    }

    #[test]
    fn clipping_to_a_box_keeps_the_inside() {
        let b = Bounds {
            min: DVec3::new(0.0, -1.0, 0.0),
            max: DVec3::new(1.0, 1.0, 1.0),
        };
        // A 4 x 4 square in y = 0 centred on the box's corner column: a quarter inside.
        let square = vec![
            DVec3::new(-2.0, 0.0, -2.0),
            DVec3::new(2.0, 0.0, -2.0),
            DVec3::new(2.0, 0.0, 2.0),
            DVec3::new(-2.0, 0.0, 2.0),
        ];
        let p = clip_to_box(square, b);
        let area: f64 = (2..p.len())
            .map(|k| 0.5 * (p[k - 1] - p[0]).cross(p[k] - p[0]).length())
            .sum();
        assert!((area - 1.0).abs() < 1e-12, "{area}: {p:?}");
        let above = vec![
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(1.0, 2.0, 0.0),
            DVec3::Y * 3.0,
        ];
        assert!(clip_to_box(above, b).is_empty());
    }

    #[test]
    fn point_lights_hover_over_surfaces_within_reach() {
        let s = cbr_scene::builtin("demo").expect("demo");
        let region = points_region(&s, 32.0);
        let lights = random_point_lights(&s, 200, 32.0);
        assert_eq!(
            format!("{lights:?}"),
            format!("{:?}", random_point_lights(&s, 200, 32.0))
        );
        let range = f64::from(lights[0].range);
        for l in &lights {
            let p = DVec3::from(l.position);
            // Within the region grown by the largest hover height.
            let grow = 0.12 * range + 1e-9;
            assert!(p.cmpge(region.min - grow).all() && p.cmple(region.max + grow).all());
        }
        // The demo's region is mostly ground: most lights hover low over it.
        let low = lights
            .iter()
            .filter(|l| l.position[1] < 0.12 * range + 1e-9)
            .count();
        assert!(low > 100, "{low} of 200 lights near the ground");
    }

    #[test]
    fn the_region_is_the_scene_within_reach() {
        let b = Bounds {
            min: DVec3::new(-600.0, 0.0, -600.0),
            max: DVec3::new(600.0, 140.0, 600.0),
        };
        let r = framed_region(b, DVec3::new(10.0, 2.0, -5.0), 32.0).expect("in reach");
        assert_eq!(r.min, DVec3::new(-22.0, 0.0, -37.0));
        assert_eq!(r.max, DVec3::new(42.0, 34.0, 27.0));
        assert!(framed_region(b, DVec3::new(0.0, 500.0, 0.0), 32.0).is_none());
    }
}
