//! `<transform>` elements of the Mitsuba loader → one matrix. Mitsuba applies the children in
//! document order, each after the previous ones: the result is `last * ... * first`, so
//! `<scale/><rotate/><translate/>` scales first and translates last.

use glam::{Mat3, Mat4, Vec3};
use roxmltree::Node;

use crate::camera::look_at_matrix;
use crate::error::{ErrorKind, SceneError};

use super::props::Ctx;

pub(crate) fn parse_transform(ctx: &mut Ctx, node: Node) -> Result<Mat4, SceneError> {
    let mut m = Mat4::IDENTITY;
    for op in node.children().filter(Node::is_element) {
        let step = match op.tag_name().name() {
            "translate" => Mat4::from_translation(ctx.vec3_attrs(op, 0.0)?),
            "scale" => {
                let s = match ctx.attr(op, "value")? {
                    Some(v) => match ctx.numbers(op, &v)?.as_slice() {
                        [s] => Vec3::splat(*s as f32),
                        [x, y, z] => Vec3::new(*x as f32, *y as f32, *z as f32),
                        _ => {
                            return Err(ctx.err(
                                op,
                                ErrorKind::Syntax,
                                "scale needs 1 or 3 numbers",
                            ))
                        }
                    },
                    None => ctx.vec3_attrs(op, 1.0)?,
                };
                Mat4::from_scale(s)
            }
            "rotate" => {
                let axis = ctx.vec3_attrs(op, 0.0)?;
                let angle = ctx.number(op, &ctx.req_attr(op, "angle")?)?;
                let Some(axis) = axis.try_normalize() else {
                    return Err(ctx.err(op, ErrorKind::Syntax, "rotation axis is zero"));
                };
                Mat4::from_axis_angle(axis, (angle as f32).to_radians())
            }
            "matrix" => {
                let v = ctx.numbers(op, &ctx.req_attr(op, "value")?)?;
                let v: Vec<f32> = v.iter().map(|&x| x as f32).collect();
                // Mitsuba writes matrices row by row; glam builds from columns.
                match v.len() {
                    16 => Mat4::from_cols_array(&v.try_into().unwrap_or([0.0; 16])).transpose(),
                    9 => Mat4::from_mat3(
                        Mat3::from_cols_array(&v.try_into().unwrap_or([0.0; 9])).transpose(),
                    ),
                    n => {
                        return Err(ctx.err(
                            op,
                            ErrorKind::Syntax,
                            format!("matrix needs 16 (or 9) numbers, got {n}"),
                        ))
                    }
                }
            }
            "lookat" => {
                let origin = ctx.vec3_text(op, &ctx.req_attr(op, "origin")?)?;
                let target = ctx.vec3_text(op, &ctx.req_attr(op, "target")?)?;
                let up = match ctx.attr(op, "up")? {
                    Some(u) => ctx.vec3_text(op, &u)?,
                    // Mitsuba picks any vector perpendicular to the view direction.
                    None => (target - origin)
                        .try_normalize()
                        .map_or(Vec3::Y, |d| d.any_orthonormal_vector()),
                };
                look_at_matrix(origin, target, up).ok_or_else(|| {
                    ctx.err(
                        op,
                        ErrorKind::Syntax,
                        "lookat: origin equals target, or up is parallel to the view direction",
                    )
                })?
            }
            other => {
                ctx.warn(op, format!("unknown transform operation <{other}> ignored"));
                continue;
            }
        };
        m = step * m;
    }
    if !m.is_finite() {
        return Err(ctx.err(node, ErrorKind::Syntax, "transform is not finite"));
    }
    Ok(m)
}
