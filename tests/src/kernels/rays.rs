//! Struct-heavy: derived structs in buffers, field reads and writes, struct literals,
//! `let mut` structs, vector methods and `if` as a value.
use cohort::prelude::*;

#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Ray {
    pub origin: Vec3,
    pub tmin: f32,
    pub dir: Vec3,
    pub tmax: f32,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Hit {
    pub normal: Vec3,
    pub t: f32,
    pub sphere: u32,
    pub hit: u32,
    pub pad: [u32; 2],
}

#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

/// Distance along `ray` to `s`, or a negative number.
#[kernel_fn]
pub fn hit_sphere(ray: Ray, s: Sphere) -> f32 {
    let oc = ray.origin - s.center;
    let b = oc.dot(ray.dir);
    let c = oc.dot(oc) - s.radius * s.radius;
    let disc = b * b - c;
    if disc < 0.0 {
        -1.0
    } else {
        let root = disc.sqrt();
        let near = -b - root;
        if near > ray.tmin {
            near
        } else {
            -b + root
        }
    }
}

#[kernel(workgroup = 64)]
pub fn trace_spheres(
    #[builtin(global_index)] i: u32,
    rays: &[Ray],
    spheres: &[Sphere],
    hits: &mut [Hit],
) {
    let i = i as usize;
    if i >= rays.len() {
        return;
    }
    let ray = rays[i];
    let mut best = Hit {
        normal: Vec3::ZERO,
        t: ray.tmax,
        sphere: 0,
        hit: 0,
        pad: [0, 0],
    };
    for s in 0..spheres.len() {
        let t = hit_sphere(ray, spheres[s]);
        if t > ray.tmin && t < best.t {
            best.t = t;
            best.sphere = s as u32;
            best.hit = 1;
            let p = ray.origin + ray.dir * t;
            best.normal = (p - spheres[s].center).normalize();
        }
    }
    hits[i] = best;
}
