// `ours`' fallback in passes of its own (`interleaved:...:fallback=pairs`, the default without
// `direct`; docs/interleaved.md, "The fallback in passes of its own"). The lighting pass lists each
// pixel that has window slots off its surface (an entry: the pixel, its colour before the VPL term
// and its found estimates' sum) and, contiguous in slot order, one pair (pixel, subset) per
// missing slot; `interleaved.fallback` shades one pair per invocation (every invocation the same
// loop over one subset's VPLs: no lane waits for a longer list), and `interleaved.finish` adds each
// entry's pairs in its slot order and writes the pixel: the sums and their order are the inline
// loop's (filter.glsl, shade_missing). A pixel whose pairs or entry do not fit the buffers takes
// the inline loop.
//
// The counters and both indirect dispatches (lighting.rs resets them each frame): entries and pairs
// allocated (beyond the capacities where they overflowed), a word unused, the fallback's and the
// finish's group counts, and the buffers' capacities.
// The fallback passes' work groups (lighting.rs, `FALLBACK_GROUP`).
const uint FALLBACK_GROUP = 64u;

struct FallbackEntry {
    uvec4 meta;   // x: pixel x | y << 16; y: its first pair; z: its pairs
    vec4 color;   // rgb: the pixel's colour before the VPL term
    vec4 sum;     // rgb: the sum of the estimates its window found on its surface
};

#ifdef BINDING_FALLBACK_ARGS
layout(std430, set = 0, binding = BINDING_FALLBACK_ARGS) buffer FallbackArgs {
    uint f_entries;
    uint f_pairs;
    uint f_unused;
    uint f_pad;
    uint f_pair_groups[3];
    uint f_entry_groups[3];
    uint f_entry_cap;
    uint f_pair_cap;
};
#endif
#ifdef BINDING_FALLBACK_ENTRIES
layout(std430, set = 0, binding = BINDING_FALLBACK_ENTRIES) buffer FallbackEntries {
    FallbackEntry f_entry[];
};
#endif
// A pair: pixel x | y << 13 | subset << 26.
#ifdef BINDING_FALLBACK_PAIRS
layout(std430, set = 0, binding = BINDING_FALLBACK_PAIRS) buffer FallbackPairs { uint f_pair[]; };
#endif
// Per pair its subset's irradiance times M N (three floats).
#ifdef BINDING_FALLBACK_RESULTS
layout(std430, set = 0, binding = BINDING_FALLBACK_RESULTS) buffer FallbackResults {
    float f_result[];
};
#endif

uint pack_pair(ivec2 px, uint k) { return uint(px.x) | (uint(px.y) << 13) | (k << 26); }
ivec2 pair_pixel(uint pair) { return ivec2(int(pair & 0x1fffu), int((pair >> 13) & 0x1fffu)); }
uint pair_subset(uint pair) { return pair >> 26; }
