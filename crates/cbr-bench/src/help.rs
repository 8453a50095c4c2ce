//! The `cbr bench` flags' help texts that name techniques (the binary's arguments do not). They
//! end without a period, as clap shows a one-paragraph doc comment.

/// `--techniques`.
pub const TECHNIQUES: &str = "Configurations, comma-separated technique specs (`cbr info` lists \
    the registered ones): native, ssaa:N, msaa:N[:sample][:hdr], upscale:bilinear|bicubic, \
    checkerboard:LAYOUT[:MODE][:pixel|quad][:8|16][:fp16][:prepass][:locations] (MODE: ours, \
    pq4k, intel, spatial, temporal; default ours, quad, 8), each with post passes (+sharpen). \
    The reference and native are always run";
/// `--mappings`.
pub const MAPPINGS: &str =
    "Sweep: resolve mappings for every checkerboard configuration that does not name one";
/// `--groups`.
pub const GROUPS: &str =
    "Sweep: resolve group sizes for every checkerboard configuration that does not name one";
/// `--lod-biases`.
pub const LOD_BIASES: &str =
    "Sweep: texture LOD biases for checkerboard configurations (default: each layout's own)";
/// `--reference`.
pub const REFERENCE: &str = "The reference every error is measured against: `native` \
    (reconstruction error) or a supersampled ground truth such as `ssaa:16` (then native gets an \
    error row too). Its frames are cached on disk (see --no-cache)";
/// `--time-cached-rows`.
pub const TIME_CACHED_ROWS: &str = "Render and time cacheable techniques among the rows (ssaa:N) \
    instead of reading their frames from the cache; the reference still comes from the cache";
