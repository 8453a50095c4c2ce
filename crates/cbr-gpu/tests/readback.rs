//! A host-visible buffer's bytes are the bytes asked for, not its allocation's: drivers round a
//! buffer's memory requirements up (the NVIDIA driver 580 on an H100 did; lavapipe's came back
//! exact, 5 bytes for 5, so this test cannot fail there), and the mapped slice of the allocation
//! is as long as the requirements. Found
//! by the GPU study (docs/resolve.md): a 61x37 `R32_UINT` readback came back as more than 2257
//! values there, and the interlaced test indexed past its CPU reference.

mod common;

use cbr_gpu::{Buffer, Location, Readback, vk};

#[test]
fn host_visible_buffers_show_exactly_their_size() {
    let gpu = common::gpu();
    // Sizes that are not multiples of 4, 16, 64 or 256, and the image readbacks of odd sizes.
    for size in [5u64, 7, 13, 61, 255, 257, 1001, 9028, 4097 * 3] {
        for location in [Location::GpuToCpu, Location::CpuToGpu] {
            let b = Buffer::new(
                &gpu,
                "test.readback",
                size,
                vk::BufferUsageFlags::TRANSFER_DST,
                location,
            )
            .expect("buffer");
            assert_eq!(
                b.bytes().expect("mapped").len() as u64,
                size,
                "{location:?}"
            );
        }
    }
    for (w, h) in [(61u32, 37u32), (1, 1), (3, 5), (127, 9)] {
        let rb = Readback::for_buffer(&gpu, "test.readback", u64::from(w * h) * 4, w, h)
            .expect("readback");
        assert_eq!(rb.bytes().expect("mapped").len(), (w * h * 4) as usize);
    }
    assert!(
        gpu.validation().messages().is_empty(),
        "{:?}",
        gpu.validation().messages()
    );
}
