//! The display transform: linear HDR radiance to the 8-bit image a person sees, and the space in
//! which PSNR, SSIM and LDR-FLIP are computed. Fixed and documented so numbers are comparable:
//!
//! 1. exposure: `x * 2^stops`;
//! 2. tonemap: Narkowicz's fit of the ACES filmic curve,
//!    `(x (2.51 x + 0.03)) / (x (2.43 x + 0.59) + 0.14)`, per channel;
//! 3. clamp to [0, 1], then the sRGB OETF (IEC 61966-2-1).
//!
//! Non-finite inputs map to 0 (metrics count them separately).

use serde::Serialize;

#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct DisplayTransform {
    pub exposure_stops: f32,
}

impl Default for DisplayTransform {
    fn default() -> Self {
        DisplayTransform {
            exposure_stops: 0.0,
        }
    }
}

pub fn aces_narkowicz(x: f32) -> f32 {
    let x = x.max(0.0);
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

pub fn srgb_oetf(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

impl DisplayTransform {
    pub fn describe(&self) -> String {
        format!(
            "exposure {:+} stops, ACES filmic (Narkowicz 2015 fit), clamp [0,1], sRGB OETF",
            self.exposure_stops
        )
    }

    /// One linear channel to a display value in [0, 1].
    pub fn apply(&self, x: f32) -> f32 {
        if !x.is_finite() {
            return 0.0;
        }
        srgb_oetf(aces_narkowicz(x * self.exposure_stops.exp2()))
    }

    /// RGBA half-float pixels to RGBA8 (alpha kept, clamped).
    pub fn to_rgba8(&self, rgba: &[half::f16]) -> Vec<u8> {
        let q = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
        rgba.chunks_exact(4)
            .flat_map(|p| {
                [
                    q(self.apply(p[0].to_f32())),
                    q(self.apply(p[1].to_f32())),
                    q(self.apply(p[2].to_f32())),
                    q(p[3].to_f32()),
                ]
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        let d = DisplayTransform::default();
        assert_eq!(d.apply(0.0), 0.0);
        assert!(d.apply(1e6) > 0.999);
        // ACES fit at 0.18: 0.2669..., sRGB-encoded: 0.5535...
        assert!(
            (aces_narkowicz(0.18) - 0.266_98).abs() < 1e-4,
            "{}",
            aces_narkowicz(0.18)
        );
        assert!((srgb_oetf(0.5) - 0.735_36).abs() < 1e-4);
        assert_eq!(d.apply(f32::NAN), 0.0);
        let brighter = DisplayTransform {
            exposure_stops: 1.0,
        };
        assert!((brighter.apply(0.09) - d.apply(0.18)).abs() < 1e-6);
    }

    #[test]
    fn monotonic() {
        let d = DisplayTransform::default();
        let mut last = -1.0;
        for i in 0..1000 {
            let v = d.apply(i as f32 * 0.01);
            assert!(v >= last);
            last = v;
        }
    }
}
