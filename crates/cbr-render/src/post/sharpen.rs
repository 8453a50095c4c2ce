//! `+sharpen[:AMOUNT]`: a 5-tap unsharp mask on linear HDR colour,
//! `out = max(c + a (4 c - n - s - e - w), 0)` per channel, edges clamped, alpha 1
//! (shaders/post/sharpen.comp). The simplest post pass: it exercises the chain, and its CPU
//! reference [`reference`] holds the shader to the formula.

use cbr_gpu::{Cmd, Image, Profiler, Result};

use super::{PostBuildCtx, PostFrame, PostPass, PostRegistration};
use crate::pass::{Binding, Binds, ComputeDecl, ComputePass, ResourceDecl, Resources, Use};
use crate::targets::COLOR_FORMAT;

pub const REGISTRATION: PostRegistration = PostRegistration {
    name: "sharpen",
    grammar: "sharpen[:AMOUNT]",
    about: "5-tap unsharp mask on linear HDR colour (AMOUNT 0..4, default 0.5)",
    check: |p| parse(p).map(|_| ()),
    geometry: false,
    estimate: |ctx, _| crate::pass::estimate(&resources(ctx.width, ctx.height), "sharpen"),
    passes: |p, _| {
        parse(p)?;
        Ok(vec![decl()])
    },
    build: |ctx, p| {
        let amount = parse(p).map_err(|e| super::refused("sharpen", p, e))?;
        Ok(Box::new(Sharpen::new(ctx, amount)?))
    },
};

pub const DEFAULT_AMOUNT: f32 = 0.5;

fn parse(params: &[&str]) -> std::result::Result<f32, String> {
    match params {
        [] => Ok(DEFAULT_AMOUNT),
        [a] => match a.parse::<f32>() {
            Ok(v) if (0.0..=4.0).contains(&v) => Ok(v),
            _ => Err(format!("sharpen amount `{a}` (a number from 0 to 4)")),
        },
        [_, extra, ..] => Err(format!("`{extra}`: sharpen takes one amount")),
    }
}

crate::push_constants! {
    struct Push {
        /// W, H, amount, 0.
        size_amount: [f32; 4],
    }
}

/// The pass (shaders/post/sharpen.comp).
pub fn decl() -> ComputeDecl {
    ComputeDecl::new("sharpen", "post/sharpen.comp")
        .bind(Binding::sampled("src"))
        .bind(Binding::image("out", Use::Write))
        .push::<Push>()
}

fn resources(w: u32, h: u32) -> Vec<ResourceDecl> {
    vec![ResourceDecl::image("out", COLOR_FORMAT, w, h)]
}

pub struct Sharpen {
    pass: ComputePass,
    res: Resources,
    push: Push,
}

impl Sharpen {
    fn new(ctx: &PostBuildCtx, amount: f32) -> Result<Sharpen> {
        Ok(Sharpen {
            pass: decl().build(ctx.gpu, ctx.shaders)?,
            res: Resources::new(ctx.gpu, "sharpen", &resources(ctx.width, ctx.height))?,
            push: Push {
                size_amount: [ctx.width as f32, ctx.height as f32, amount, 0.0],
            },
        })
    }
}

impl PostPass for Sharpen {
    fn record(
        &mut self,
        cmd: &mut Cmd,
        profiler: &mut Profiler,
        _frame: &PostFrame,
        input: &Image,
    ) -> Result<()> {
        let binds = Binds::of(&self.res).image("src", input);
        let size = (
            self.push.size_amount[0] as u32,
            self.push.size_amount[1] as u32,
        );
        self.pass
            .dispatch_2d(cmd, profiler, &binds, &self.push, size)
    }

    fn output(&self, _frame: u32) -> Result<&Image> {
        self.res.image("out")
    }
}

/// The CPU reference: RGBA in, RGBA out (alpha 1), edges clamped, f32 arithmetic in the
/// shader's order.
pub fn reference(width: usize, height: usize, rgba: &[f32], amount: f32) -> Vec<f32> {
    let at = |x: isize, y: isize, c: usize| {
        let x = x.clamp(0, width as isize - 1) as usize;
        let y = y.clamp(0, height as isize - 1) as usize;
        rgba[4 * (y * width + x) + c]
    };
    let mut out = vec![0.0; width * height * 4];
    for y in 0..height as isize {
        for x in 0..width as isize {
            let o = 4 * (y as usize * width + x as usize);
            for c in 0..3 {
                let m = at(x, y, c);
                let n = at(x, y - 1, c) + at(x, y + 1, c) + at(x - 1, y, c) + at(x + 1, y, c);
                out[o + c] = (m + amount * (4.0 * m - n)).max(0.0);
            }
            out[o + 3] = 1.0;
        }
    }
    out
}
