// The reflective shadow map pass's push constants: `RsmPush` of
// crates/cbr-render/src/techniques/deferred/rsm.rs, its GLSL block generated from the Rust struct.
PUSH_CONSTANTS
