//! `+sharpen[:AMOUNT]`: a 5-tap unsharp mask on linear HDR colour,
//! `out = max(c + a (4 c - n - s - e - w), 0)` per channel, edges clamped, alpha 1
//! (shaders/post/sharpen.comp). The simplest post pass: it exercises the chain, and its CPU
//! reference [`reference`] holds the shader to the formula.

use cbr_gpu::{
    Access, BindingDesc, Cmd, ComputeDesc, DescriptorKind, DescriptorSet, Image, PassKind,
    Pipeline, Profiler, Result, Sampler, SamplerDesc, SetLayout, Write,
};

use super::{PostBuildCtx, PostFrame, PostPass, PostRegistration};
use crate::memory::MemoryEstimate;
use crate::targets::COLOR_FORMAT;

pub const REGISTRATION: PostRegistration = PostRegistration {
    name: "sharpen",
    grammar: "sharpen[:AMOUNT]",
    about: "5-tap unsharp mask on linear HDR colour (AMOUNT 0..4, default 0.5)",
    check: |p| parse(p).map(|_| ()),
    geometry: false,
    estimate: |ctx, _| {
        let mut e = MemoryEstimate::new();
        e.image("sharpen.out", COLOR_FORMAT, ctx.width, ctx.height);
        e
    },
    build: |ctx, p, inputs| {
        let amount = parse(p).map_err(cbr_gpu::GpuError::Other)?;
        Ok(Box::new(Sharpen::new(ctx, amount, inputs)?))
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

pub const BINDINGS: [BindingDesc; 2] = [
    BindingDesc::one("src", 0, DescriptorKind::CombinedImageSampler),
    BindingDesc::one("dst", 1, DescriptorKind::StorageImage),
];

pub struct Sharpen {
    pipeline: Pipeline,
    _layout: SetLayout,
    sets: Vec<DescriptorSet>,
    _sampler: Sampler,
    out: Image,
    push: [f32; 4],
}

impl Sharpen {
    fn new(ctx: &PostBuildCtx, amount: f32, inputs: &[&Image]) -> Result<Sharpen> {
        let gpu = ctx.gpu;
        let layout = SetLayout::new(gpu, "sharpen.set_layout", &BINDINGS)?;
        let defines: Vec<(String, String)> = BINDINGS.iter().map(BindingDesc::define).collect();
        let cs = ctx.shaders.compile("post/sharpen.comp", &defines)?;
        let pipeline = Pipeline::compute(
            gpu,
            &ComputeDesc {
                name: "sharpen",
                shader: &cs,
                set_layouts: &[&layout],
                push_constant_bytes: 16,
            },
        )?;
        let sampler = Sampler::new(gpu, "sharpen.sampler", SamplerDesc::NEAREST)?;
        let out = ctx.output("sharpen.out")?;
        let sets = ctx.sets_per_input(
            "sharpen.set",
            &layout,
            inputs,
            &sampler,
            &[Write::Storage(1, &out)],
        )?;
        Ok(Sharpen {
            pipeline,
            _layout: layout,
            sets,
            _sampler: sampler,
            out,
            push: [ctx.width as f32, ctx.height as f32, amount, 0.0],
        })
    }
}

impl PostPass for Sharpen {
    fn record(&self, cmd: &mut Cmd, profiler: &mut Profiler, frame: &PostFrame, input: &Image) {
        let k = frame.frame as usize % self.sets.len();
        cmd.use_image(input, Access::ComputeSampled);
        cmd.use_image(&self.out, Access::ComputeStorageWrite);
        let scope = profiler.begin(cmd, "sharpen", PassKind::Compute);
        cmd.bind_pipeline(&self.pipeline);
        cmd.bind_set(&self.pipeline, 0, &self.sets[k]);
        cmd.push_constants(&self.pipeline, bytemuck::cast_slice(&self.push));
        cmd.dispatch(self.out.width.div_ceil(8), self.out.height.div_ceil(8), 1);
        profiler.end(cmd, scope);
    }

    fn output(&self, _frame: u32) -> &Image {
        &self.out
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
