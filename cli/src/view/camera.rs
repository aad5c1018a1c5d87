//! Camera control of the viewer: orbit around a pivot (the scene's look-at point, as
//! far as a camera matrix remembers it), pan, dolly, and fly along the camera's axes.
//! Every move yields a new `Camera`; the renderer restarts its accumulation from it.

use cohort_scenes::Camera;
use glam::{Mat4, Quat, Vec3};

/// Radians of orbit per pixel of mouse drag.
const ORBIT_PER_PIXEL: f32 = 0.005;

pub struct CameraControl {
    home: Camera,
    home_pivot: Vec3,
    /// The axis of horizontal orbiting: the scene camera's up, fixed while moving.
    world_up: Vec3,
    /// A length of the scene's size: fly and pan steps are fractions of it.
    scale: f32,
    camera: Camera,
    pivot: Vec3,
}

impl CameraControl {
    /// `bounds`: the scene's geometry (`None` when it has none). The pivot is where the
    /// view axis passes closest to the bounds' centre, in front of the camera.
    pub fn new(camera: Camera, bounds: Option<(Vec3, Vec3)>) -> CameraControl {
        let origin = camera.origin();
        let forward = camera.to_world.transform_vector3(Vec3::Z).normalize();
        let (center, radius) = match bounds {
            Some((lo, hi)) => (0.5 * (lo + hi), (0.5 * (hi - lo).length()).max(1e-3)),
            None => (origin + forward, 1.0),
        };
        let along = (center - origin).dot(forward).max(0.1 * radius);
        let pivot = origin + forward * along;
        CameraControl {
            home: camera,
            home_pivot: pivot,
            world_up: camera.up(),
            scale: radius,
            camera,
            pivot,
        }
    }

    pub fn camera(&self) -> Camera {
        self.camera
    }

    /// Back to the scene's camera.
    pub fn reset(&mut self) {
        self.camera = self.home;
        self.pivot = self.home_pivot;
    }

    /// Image-right in world space (camera space +x points left, as in Mitsuba).
    fn right(&self) -> Vec3 {
        self.camera
            .to_world
            .transform_vector3(Vec3::NEG_X)
            .normalize()
    }

    fn up(&self) -> Vec3 {
        self.camera.up()
    }

    fn forward(&self) -> Vec3 {
        self.camera.to_world.transform_vector3(Vec3::Z).normalize()
    }

    /// Rigid motion `m` applied to the camera (and the pivot, when `move_pivot`).
    fn apply(&mut self, m: Mat4, move_pivot: bool) {
        self.camera.to_world = m * self.camera.to_world;
        if move_pivot {
            self.pivot = m.transform_point3(self.pivot);
        }
    }

    /// A drag of (dx, dy) pixels: the camera turns around the pivot, left-right about
    /// the scene's up, up-down about the image's horizontal axis.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        let yaw = Quat::from_axis_angle(self.world_up, -dx * ORBIT_PER_PIXEL);
        let pitch = Quat::from_axis_angle(self.right(), -dy * ORBIT_PER_PIXEL);
        let rotate = Mat4::from_translation(self.pivot)
            * Mat4::from_quat(yaw * pitch)
            * Mat4::from_translation(-self.pivot);
        self.apply(rotate, false);
    }

    /// A drag of (dx, dy) pixels that moves the camera and the pivot in the image plane.
    pub fn pan(&mut self, dx: f32, dy: f32) {
        let step = self.scale * 0.002;
        let t = (-dx * self.right() + dy * self.up()) * step;
        self.apply(Mat4::from_translation(t), true);
    }

    /// Toward the pivot (`steps` > 0) or away from it, by a tenth of the distance per step.
    pub fn dolly(&mut self, steps: f32) {
        let to_pivot = self.pivot - self.camera.origin();
        let t = to_pivot * (1.0 - 0.9f32.powf(steps));
        self.apply(Mat4::from_translation(t), false);
    }

    /// A step of flight along the camera's axes: (right, up, forward) in steps of a
    /// fortieth of the scene's size; the pivot moves along.
    pub fn fly(&mut self, right: f32, up: f32, forward: f32) {
        let step = self.scale / 40.0;
        let t = (right * self.right() + up * self.up() + forward * self.forward()) * step;
        self.apply(Mat4::from_translation(t), true);
    }
}

/// The bounds of the scene's triangles (`None` without geometry).
pub fn scene_bounds(scene: &cohort_scenes::Scene) -> Option<(Vec3, Vec3)> {
    let p = &scene.triangles.positions;
    let finite = p.iter().filter(|v| v.is_finite());
    let lo = finite
        .clone()
        .fold(None, |a: Option<Vec3>, v| Some(a.map_or(*v, |a| a.min(*v))))?;
    let hi = finite.fold(lo, |a, v| a.max(*v));
    Some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use cohort_scenes::FovAxis;

    fn camera() -> Camera {
        Camera::look_at(
            Vec3::new(0.0, 1.0, 5.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::Y,
            40.0,
            FovAxis::X,
            64,
            64,
        )
        .unwrap()
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_pivot_and_reset_returns_home() {
        let bounds = Some((Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0)));
        let mut c = CameraControl::new(camera(), bounds);
        assert!((c.pivot - Vec3::new(0.0, 1.0, 0.0)).length() < 1e-5);
        c.orbit(100.0, 0.0);
        let o = c.camera().origin();
        assert!((o.distance(Vec3::new(0.0, 1.0, 0.0)) - 5.0).abs() < 1e-4);
        assert!((o.x).abs() > 1.0, "a horizontal drag moves sideways: {o}");
        assert!((o.y - 1.0).abs() < 1e-4, "about the up axis: {o}");
        // Still looking at the pivot.
        let f = c.camera().to_world.transform_vector3(Vec3::Z).normalize();
        assert!(f.dot((Vec3::new(0.0, 1.0, 0.0) - o).normalize()) > 0.9999);
        c.dolly(1.0);
        assert!((c.camera().origin().distance(c.pivot) - 4.5).abs() < 1e-4);
        c.fly(0.0, 0.0, 1.0);
        c.pan(10.0, 10.0);
        c.reset();
        assert_eq!(c.camera().to_world, camera().to_world);
    }

    #[test]
    fn fly_moves_along_the_view_and_image_right_is_right() {
        let mut c = CameraControl::new(camera(), None);
        c.fly(1.0, 0.0, 0.0);
        // Looking down -z with +y up, image-right is +x.
        assert!(c.camera().origin().x > 0.0);
        c.reset();
        c.fly(0.0, 0.0, 1.0);
        assert!(c.camera().origin().z < 5.0);
    }
}
