//! `<transform>` elements of the Mitsuba loader → one matrix. Mitsuba applies the children in
//! document order, each after the previous ones: the result is `last * ... * first`, so
//! `<scale/><rotate/><translate/>` scales first and translates last.

use glam::{Mat3, Mat4, Vec3};

use crate::camera::look_at_matrix;
use crate::error::SceneError;

use super::diag::{syntax, Diag};
use super::props::{number, numbers, vec3_text, xyz};
use super::xml::{check_attrs, Elem};

pub(crate) fn parse_transform(diag: &mut Diag, e: &Elem) -> Result<Mat4, SceneError> {
    let mut m = Mat4::IDENTITY;
    for op in &e.children {
        let loc = &op.loc;
        let tag = op.tag.as_str();
        let step = match tag {
            "translate" => {
                check_attrs(diag, loc, tag, &op.attrs, &["value", "x", "y", "z"])?;
                Mat4::from_translation(xyz(op, Some(0.0))?)
            }
            "scale" => {
                check_attrs(diag, loc, tag, &op.attrs, &["value", "x", "y", "z"])?;
                Mat4::from_scale(xyz(op, Some(1.0))?)
            }
            "rotate" => {
                check_attrs(
                    diag,
                    loc,
                    tag,
                    &op.attrs,
                    &["!angle", "value", "x", "y", "z"],
                )?;
                let axis = xyz(op, Some(0.0))?;
                let angle = number(loc, op.attr("angle").unwrap_or_default())?;
                let Some(axis) = axis.try_normalize() else {
                    return Err(syntax(loc, "rotation axis is zero"));
                };
                Mat4::from_axis_angle(axis, (angle as f32).to_radians())
            }
            "matrix" => {
                check_attrs(diag, loc, tag, &op.attrs, &["!value"])?;
                let v = numbers(loc, op.attr("value").unwrap_or_default())?;
                let v: Vec<f32> = v.iter().map(|&x| x as f32).collect();
                // Mitsuba writes matrices row by row; glam builds from columns.
                match v.len() {
                    16 => Mat4::from_cols_slice(&v).transpose(),
                    9 => Mat4::from_mat3(Mat3::from_cols_slice(&v).transpose()),
                    n => {
                        return Err(syntax(
                            loc,
                            format!("matrix needs 16 (or 9) numbers, got {n}"),
                        ))
                    }
                }
            }
            "lookat" => {
                check_attrs(diag, loc, tag, &op.attrs, &["!origin", "!target", "up"])?;
                let origin = vec3_text(loc, op.attr("origin").unwrap_or_default())?;
                let target = vec3_text(loc, op.attr("target").unwrap_or_default())?;
                let up = match op.attr("up") {
                    Some(u) => vec3_text(loc, u)?,
                    None => Vec3::ZERO,
                };
                // Mitsuba: a missing or zero `up` is the first vector of its
                // `coordinate_system(direction)`.
                let up = if up == Vec3::ZERO {
                    (target - origin)
                        .try_normalize()
                        .map_or(Vec3::Y, coordinate_system_s)
                } else {
                    up
                };
                look_at_matrix(origin, target, up).ok_or_else(|| {
                    syntax(
                        loc,
                        "lookat: origin equals target, or up is parallel to the view direction",
                    )
                })?
            }
            other => {
                diag.unsupported(
                    loc,
                    format!("unknown transform operation <{other}>"),
                    "ignored",
                )?;
                continue;
            }
        };
        m = step * m;
    }
    if !m.is_finite() {
        return Err(syntax(&e.loc, "transform is not finite"));
    }
    Ok(m)
}

/// The first tangent of Mitsuba's `coordinate_system(n)` (Duff et al. 2017).
fn coordinate_system_s(n: Vec3) -> Vec3 {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x)
}
