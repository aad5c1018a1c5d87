//! A kernel's parameters may take any name, also those of the generated launch functions'
//! own parameters and locals (`device`, `grid`, `spec`, `batch`, `art`, `dispatch`) and
//! of the module's functions (`artifact`, `launch_spec`): the generated code keeps its
//! names apart (`__cohort_*`, `self::`). Once a kernel with a `grid` parameter failed to
//! compile with "identifier `grid` is bound more than once".

mod common;

use cohort::prelude::*;

#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Scale {
    pub factor: u32,
    pub offset: u32,
    pub pad0: u32,
    pub pad1: u32,
}

#[kernel(workgroup = 64)]
#[allow(clippy::too_many_arguments)]
pub fn named_like_the_launch(
    #[builtin(global_index)] gi: u32,
    device: &[u32],
    grid: &[u32],
    spec: &Scale,
    art: &[u32],
    dispatch: &[u32],
    artifact: &[u32],
    launch_spec: &[u32],
    batch: &mut [u32],
) {
    let i = gi as usize;
    if i < batch.len() {
        batch[i] = (device[i] + grid[i] + art[i] + dispatch[i] + artifact[i] + launch_spec[i])
            * spec.factor
            + spec.offset;
    }
}

#[test]
fn parameters_named_like_the_generated_code() {
    let n = 100usize;
    let input = |k: u32| (0..n as u32).map(|i| i * k).collect::<Vec<u32>>();
    let spec = Scale {
        factor: 3,
        offset: 7,
        ..Default::default()
    };
    let expect: Vec<u32> = (0..n as u32).map(|i| i * 21 * 3 + 7).collect();
    for d in common::devices() {
        let bufs: Vec<_> = (1..=6).map(|k| d.upload(&input(k)).unwrap()).collect();
        let out = d.alloc::<u32>(n).unwrap();
        named_like_the_launch::launch(
            &d, n as u32, &bufs[0], &bufs[1], &spec, &bufs[2], &bufs[3], &bufs[4], &bufs[5], &out,
        )
        .unwrap();
        assert_eq!(d.read(&out).unwrap(), expect, "{}", d.info().adapter_name);
        let mut b = d.batch();
        let s = named_like_the_launch::spec(&d, None);
        named_like_the_launch::record(
            &mut b, &s, n as u32, &bufs[0], &bufs[1], &spec, &bufs[2], &bufs[3], &bufs[4],
            &bufs[5], &out,
        )
        .unwrap();
        b.submit().unwrap();
        assert_eq!(d.read(&out).unwrap(), expect, "{}", d.info().adapter_name);
    }
}
