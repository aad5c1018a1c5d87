//! The pinhole camera of a [`crate::Scene`], in Mitsuba's conventions (sensor `perspective` +
//! `hdrfilm`), and the small frame the renderer's camera-ray kernel needs. Sources build it from a
//! `to_world` transform; the renderer reads [`Camera::frame`].

use crate::film_filter::FilmFilter;
use glam::{Mat4, Vec2, Vec3};

/// Which image extent `fov` spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    X,
    Y,
    Diagonal,
    /// The smaller of width and height.
    Smaller,
    /// The larger of width and height.
    Larger,
}

impl FovAxis {
    pub fn parse(s: &str) -> Option<FovAxis> {
        match s.to_ascii_lowercase().as_str() {
            "x" => Some(FovAxis::X),
            "y" => Some(FovAxis::Y),
            "diagonal" => Some(FovAxis::Diagonal),
            "smaller" => Some(FovAxis::Smaller),
            "larger" => Some(FovAxis::Larger),
            _ => None,
        }
    }
}

/// How the camera maps the film to rays (Mitsuba's sensor plugin).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Projection {
    /// `perspective`: rays from the origin through the film, `fov` wide.
    #[default]
    Perspective,
    /// `orthographic`: parallel rays along the view axis from the near-clip plane; the film
    /// spans camera-space x in [-1, 1] and y in [-1/aspect, 1/aspect] (scale `to_world` to
    /// widen it), as in Mitsuba. `fov` is unused.
    Orthographic,
}

/// Perspective pinhole (or orthographic) camera with a box reconstruction filter (each sample
/// lands in the pixel it was drawn in).
///
/// `to_world` is kept whole instead of (origin, target, up) because Mitsuba allows any transform
/// before `lookat` (a common one is `scale x=-1`, a mirrored image) and those must survive;
/// [`Camera::origin`], [`Camera::target`] and [`Camera::up`] read the usual triple back out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Camera space (Mitsuba): +z forward, +y up, +x LEFT (image x runs along -x).
    pub to_world: Mat4,
    /// Full angle in degrees along `fov_axis`.
    pub fov: f32,
    pub fov_axis: FovAxis,
    pub width: u32,
    pub height: u32,
    /// Distance (along the view axis) before which nothing is seen; Mitsuba default 1e-2.
    pub near_clip: f32,
    pub far_clip: f32,
    pub projection: Projection,
    /// Mitsuba `thinlens`: radius of the lens aperture in world units (0: a pinhole). Rays
    /// start on the lens disk and meet at `focus_distance` along the view axis.
    pub aperture_radius: f32,
    pub focus_distance: f32,
    /// Mitsuba's film crop window: only this part of a larger film is rendered, and
    /// `width` x `height` is its size (the field of view and the aspect are the film's).
    pub crop: Option<CropWindow>,
    /// Mitsuba's reconstruction filter (`None`: the box, each sample in its own pixel).
    pub filter: Option<FilmFilter>,
}

/// The position of the rendered rectangle in the full film, in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CropWindow {
    pub film_width: u32,
    pub film_height: u32,
    pub offset_x: u32,
    pub offset_y: u32,
}

/// What a camera-ray kernel needs: the direction for film coordinates `(sx, sy)` in `[0,1]^2`
/// (x left to right, y top to bottom) is `forward + (2 sx - 1) right + (1 - 2 sy) up`, not
/// normalised. `right` and `up` already carry the tangent of the half field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
///
/// Orthographic cameras instead move the origin: the ray for `(sx, sy)` starts at `origin +
/// (2 sx - 1) right + (1 - 2 sy) up` and runs along `forward`.
pub struct CameraFrame {
    pub origin: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub orthographic: bool,
    /// Thin lens (perspective only): rays start at `origin` plus a uniform point of the
    /// disk of this radius spanned by `right` and `up`, and pass through `origin + (forward
    /// + film) * focus_distance`.
    pub lens_radius: f32,
    pub focus_distance: f32,
}

impl Camera {
    /// Mitsuba's `lookat`: forward = target - origin, image x along cross(forward, up).
    /// Returns `None` when `up` is parallel to the view direction or origin == target.
    pub fn look_at(
        origin: Vec3,
        target: Vec3,
        up: Vec3,
        fov: f32,
        fov_axis: FovAxis,
        width: u32,
        height: u32,
    ) -> Option<Camera> {
        Some(Camera {
            to_world: look_at_matrix(origin, target, up)?,
            fov,
            fov_axis,
            width,
            height,
            near_clip: 1e-2,
            far_clip: 1e4,
            projection: Projection::Perspective,
            aperture_radius: 0.0,
            focus_distance: 1e4,
            crop: None,
            filter: None,
        })
    }

    pub fn origin(&self) -> Vec3 {
        self.to_world.transform_point3(Vec3::ZERO)
    }

    /// A point one unit (in camera space) in front of the origin.
    pub fn target(&self) -> Vec3 {
        self.to_world.transform_point3(Vec3::Z)
    }

    pub fn up(&self) -> Vec3 {
        self.to_world.transform_vector3(Vec3::Y).normalize()
    }

    /// The aspect ratio of the whole film (of which a crop window renders a part).
    pub fn aspect(&self) -> f32 {
        match self.crop {
            Some(c) => c.film_width as f32 / c.film_height as f32,
            None => self.width as f32 / self.height as f32,
        }
    }

    /// This camera rendering `width` x `height` pixels: the same camera where that is its
    /// size, else its whole film at that size (a crop window is dropped).
    pub fn with_size(mut self, width: u32, height: u32) -> Camera {
        if (width, height) != (self.width, self.height) {
            self.crop = None;
            self.width = width;
            self.height = height;
        }
        self
    }

    /// The horizontal full field of view in degrees, converted from `fov` / `fov_axis` exactly as
    /// Mitsuba's `parse_fov` does (Mitsuba stores only the x angle).
    pub fn fov_x(&self) -> f32 {
        fov_x(self.fov, self.fov_axis, self.aspect())
    }

    /// Tangents of the half angles along image x and y.
    pub fn tan_half_fov(&self) -> (f32, f32) {
        let tx = (0.5 * self.fov_x().to_radians()).tan();
        (tx, tx / self.aspect())
    }

    /// The frame of the rendered pixels: the whole film's, narrowed to the crop window.
    pub fn frame(&self) -> CameraFrame {
        let mut f = self.film_frame();
        if let Some(c) = self.crop {
            // A rendered pixel (px, py) of w x h is film pixel (ox + px, oy + py) of W x H:
            // the film offset 2 sx - 1 becomes (2 px / w - 1) w / W + (2 ox + w) / W - 1.
            let (w, h) = (self.width as f32, self.height as f32);
            let (fw, fh) = (c.film_width as f32, c.film_height as f32);
            let shift = f.right * ((2.0 * c.offset_x as f32 + w) / fw - 1.0)
                + f.up * (1.0 - (2.0 * c.offset_y as f32 + h) / fh);
            if f.orthographic {
                f.origin += shift;
            } else {
                f.forward += shift;
            }
            f.right *= w / fw;
            f.up *= h / fh;
        }
        f
    }

    fn film_frame(&self) -> CameraFrame {
        if self.projection == Projection::Orthographic {
            // Camera x points left, so image-right is -x; rays start on the near-clip plane.
            return CameraFrame {
                origin: self
                    .to_world
                    .transform_point3(Vec3::new(0.0, 0.0, self.near_clip)),
                forward: self.to_world.transform_vector3(Vec3::Z),
                right: self.to_world.transform_vector3(Vec3::new(-1.0, 0.0, 0.0)),
                up: self
                    .to_world
                    .transform_vector3(Vec3::new(0.0, 1.0 / self.aspect(), 0.0)),
                orthographic: true,
                lens_radius: 0.0,
                focus_distance: 0.0,
            };
        }
        let (tx, ty) = self.tan_half_fov();
        // Camera x points left, so image-right is -x.
        CameraFrame {
            origin: self.origin(),
            forward: self.to_world.transform_vector3(Vec3::Z),
            right: self.to_world.transform_vector3(Vec3::new(-tx, 0.0, 0.0)),
            up: self.to_world.transform_vector3(Vec3::new(0.0, ty, 0.0)),
            orthographic: false,
            lens_radius: self.aperture_radius,
            focus_distance: self.focus_distance,
        }
    }

    /// The ray (origin, unit direction) through film point `(sx, sy)` in `[0,1]^2` (y down),
    /// through the centre of a thin lens.
    pub fn ray(&self, sx: f32, sy: f32) -> (Vec3, Vec3) {
        self.ray_through_lens(sx, sy, Vec2::ZERO)
    }

    /// The ray through film point `(sx, sy)` and the point `lens` of the unit disk (camera
    /// space x, y) scaled to the aperture (thin lens; ignored by pinhole and orthographic
    /// cameras). The kernel
    /// `cohort_kernels::extend::camera_dir` computes the same.
    pub fn ray_through_lens(&self, sx: f32, sy: f32, lens: Vec2) -> (Vec3, Vec3) {
        let f = self.frame();
        let film = (2.0 * sx - 1.0) * f.right + (1.0 - 2.0 * sy) * f.up;
        if f.orthographic {
            return (f.origin + film, f.forward.normalize());
        }
        if f.lens_radius <= 0.0 {
            return (f.origin, (f.forward + film).normalize());
        }
        // Mitsuba's aperture point (x, y, 0) is in camera space, whose x points left.
        let offset = f.lens_radius * (lens.y * f.up.normalize() - lens.x * f.right.normalize());
        let focus = (f.forward + film) * f.focus_distance;
        (f.origin + offset, (focus - offset).normalize())
    }

    /// Unit world direction through film point `(sx, sy)` in `[0,1]^2` (y down).
    pub fn ray_direction(&self, sx: f32, sy: f32) -> Vec3 {
        self.ray(sx, sy).1
    }
}

/// Mitsuba's `Transform4f::look_at`: columns (left, up', dir, origin) with
/// left = normalize(cross(up, dir)), up' = cross(dir, left).
pub fn look_at_matrix(origin: Vec3, target: Vec3, up: Vec3) -> Option<Mat4> {
    let dir = (target - origin).try_normalize()?;
    let left = up.normalize_or_zero().cross(dir).try_normalize()?;
    let new_up = dir.cross(left);
    Some(Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    ))
}

/// The horizontal full field of view in degrees of a field of view `fov` (degrees) along
/// `axis` of an image of width / height `aspect`, exactly as Mitsuba's `parse_fov` converts it.
pub fn fov_x(fov: f32, axis: FovAxis, aspect: f32) -> f32 {
    let aspect = aspect as f64;
    let axis = match axis {
        FovAxis::Smaller if aspect > 1.0 => FovAxis::Y,
        FovAxis::Smaller => FovAxis::X,
        FovAxis::Larger if aspect > 1.0 => FovAxis::X,
        FovAxis::Larger => FovAxis::Y,
        a => a,
    };
    let fov = fov as f64;
    let x = match axis {
        FovAxis::Y => {
            2.0 * ((0.5 * fov.to_radians()).tan() * aspect)
                .atan()
                .to_degrees()
        }
        FovAxis::Diagonal => {
            let diagonal = 2.0 * (0.5 * fov.to_radians()).tan();
            let width = diagonal / (1.0 + 1.0 / (aspect * aspect)).sqrt();
            2.0 * (width * 0.5).atan().to_degrees()
        }
        _ => fov,
    };
    x as f32
}
