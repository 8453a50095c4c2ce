//! Tests on RADV's null device: the driver reads `RADV_FORCE_FAMILY` once per process, so a test
//! runs an ignored test of its own binary in a child process on the family's null device.

use std::process::{Child, Command, Stdio};

use cbr_gpu::{CompileSettings, Gpu, GpuOptions, null_device};

/// `true` (with a message) where RADV's ICD is not installed: the test skips.
pub fn no_radv() -> bool {
    if null_device::radeon_icd().is_none() {
        eprintln!(
            "skipped: RADV's ICD {} is not installed",
            null_device::radeon_icd_path().display()
        );
        return true;
    }
    false
}

/// Runs the ignored test `test` of this binary in a child process on `family`'s null device,
/// with `var` set to `value`, its output piped.
pub fn spawn(test: &str, family: &str, var: &str, value: &str) -> Child {
    let mut c = Command::new(std::env::current_exe().expect("test binary"));
    c.args([test, "--exact", "--ignored", "--nocapture"]);
    null_device::set_env(&mut c, family).expect(family);
    c.env(var, value);
    c.stdout(Stdio::piped());
    c.stderr(Stdio::piped());
    c.spawn().expect("run the test binary")
}

/// The child passed its one test (its output is printed).
pub fn expect_pass(family: &str, child: Child) {
    let out = child.wait_with_output().expect("the child's output");
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!("{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{family}: {:?}", out.status);
    assert!(stdout.contains("1 passed"), "{family}: {stdout}");
}

/// In the child: the family's null device (`name`, e.g. "Null hardware (RADV VEGA10)"), with
/// validation on and `settings` for every pipeline it compiles.
pub fn gpu(name: &str, settings: CompileSettings) -> Gpu {
    let gpu = Gpu::new(&GpuOptions {
        device: None,
        validation: true,
    })
    .expect("a null device");
    assert_eq!(gpu.info().name, name);
    gpu.set_compile_settings(settings)
        .expect("compile settings");
    gpu
}
