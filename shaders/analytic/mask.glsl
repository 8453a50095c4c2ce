// `analytic`'s visibility mask: MASK_SAMPLES samples (32, 64 or 128; `analytic:samples=N`, a
// define from crates/cbr-render's analytic module), held as MASK_WORDS 32-bit words, sample s in
// bit s % 32 of word s / 32. `Mask` is uint, uvec2 or uvec4, so that &, |, ~ and == apply to the
// whole mask; the helpers below do what needs the words. MASK_GEN is the lattice's generator
// (coverage.glsl's mask_sample), a define from the same module (reference::mask_generator).
#ifndef ANALYTIC_MASK_GLSL
#define ANALYTIC_MASK_GLSL

#ifndef MASK_SAMPLES
#define MASK_SAMPLES 32
#define MASK_GEN 13
#endif
#ifndef MASK_GEN
#error "MASK_GEN (the lattice's generator) comes with MASK_SAMPLES"
#endif
#define MASK_WORDS (MASK_SAMPLES / 32)

#if MASK_SAMPLES == 32
#define Mask uint
#elif MASK_SAMPLES == 64
#define Mask uvec2
#elif MASK_SAMPLES == 128
#define Mask uvec4
#else
#error "MASK_SAMPLES must be 32, 64 or 128"
#endif

bool mask_any(Mask m) {
    return m != Mask(0u);
}

int mask_count(Mask m) {
#if MASK_WORDS == 1
    return bitCount(m);
#else
    int n = 0;
    for (int w = 0; w < MASK_WORDS; ++w) n += bitCount(m[w]);
    return n;
#endif
}

bool mask_has(Mask m, int s) {
#if MASK_WORDS == 1
    return ((m >> uint(s)) & 1u) != 0u;
#else
    return ((m[s >> 5] >> uint(s & 31)) & 1u) != 0u;
#endif
}

Mask mask_bit(int s) {
#if MASK_WORDS == 1
    return 1u << uint(s);
#else
    Mask m = Mask(0u);
    m[s >> 5] = 1u << uint(s & 31);
    return m;
#endif
}

uint mask_word(Mask m, int w) {
#if MASK_WORDS == 1
    return m;
#else
    return m[w];
#endif
}

void mask_set_word(inout Mask m, int w, uint v) {
#if MASK_WORDS == 1
    m = v;
#else
    m[w] = v;
#endif
}

// The lowest sample of a non-empty mask, taken out of it: `while (mask_any(rest)) { int s =
// mask_pop(rest); ... }` visits the samples in order.
int mask_pop(inout Mask m) {
#if MASK_WORDS == 1
    int s = findLSB(m);
    m &= m - 1u;
    return s;
#else
    for (int w = 0; w < MASK_WORDS; ++w) {
        if (m[w] != 0u) {
            int s = findLSB(m[w]);
            m[w] &= m[w] - 1u;
            return w * 32 + s;
        }
    }
    return -1;
#endif
}

#endif
