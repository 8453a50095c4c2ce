//! The `cbr bench` flags' help texts that name techniques (the binary's arguments do not). They
//! end without a period, as clap shows a one-paragraph doc comment.

/// `--techniques`.
pub fn techniques() -> String {
    format!(
        "Configurations, comma-separated technique specs: {}. The reference and native are \
         always run",
        registered()
    )
}

/// Every registered technique's grammar, then the post passes that may follow each (from the
/// registries: `cbr info` says what each does).
pub fn registered() -> String {
    let techniques: Vec<&str> = cbr_render::registry::TECHNIQUES
        .iter()
        .map(|t| t.grammar)
        .collect();
    let post: Vec<String> = cbr_render::registry::POST_PASSES
        .iter()
        .map(|p| format!("+{}", p.grammar))
        .collect();
    format!(
        "{}, each optionally followed by post passes {}",
        techniques.join(", "),
        post.join(", ")
    )
}
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
