//! What a node carries besides a mesh: a perspective camera and
//! `KHR_lights_punctual` lights, placed by the node's world transform and
//! checked for values the renderer cannot use.

use glam::{Mat4, Vec3};

use super::super::{Camera, Light, LightKind, Warnings, camera::look_at};

/// The scene camera from a glTF camera at `world`; `None` (with a warning)
/// when it is orthographic or unusable. `label` names its node.
// Not gltf::Camera::projection (gltf 1.4.1): it unwraps the object its
// `type` names, while validation only asks for one of the two objects, so a
// perspective camera with only an orthographic object panics there.
pub(super) fn camera(
    document: &gltf::Document,
    cam: &gltf::Camera,
    world: Mat4,
    label: &str,
    warnings: &mut Warnings,
) -> Option<Camera> {
    use gltf::json::camera::Type;
    use gltf::json::validation::Checked;
    let index = cam.index();
    let json = document.as_json().cameras.get(index)?;
    let p = match (json.type_, json.perspective.as_ref()) {
        (Checked::Valid(Type::Perspective), Some(p)) => p,
        (Checked::Valid(Type::Perspective), None) => {
            warnings.push(format!(
                "{label}: camera {index} is of type perspective but has no perspective object; ignored"
            ));
            return None;
        }
        (Checked::Valid(Type::Orthographic), _) => {
            warnings.push(format!(
                "{label}: orthographic cameras are not supported; looking for a perspective one"
            ));
            return None;
        }
        // Validation refuses an unknown type before the walk.
        (Checked::Invalid, _) => return None,
    };
    let (yfov, znear) = (p.yfov, p.znear);
    let usable = yfov.is_finite()
        && yfov > 0.0
        && yfov < std::f32::consts::PI
        && znear.is_finite()
        && znear > 0.0;
    if !usable {
        warnings.push(format!(
            "{label}: camera with yfov {yfov} and znear {znear} is unusable; ignored"
        ));
        return None;
    }
    let far = match p.zfar {
        Some(f) if f.is_finite() && f > znear => Some(f),
        Some(f) => {
            warnings.push(format!(
                "{label}: camera zfar {f} is not beyond znear {znear}; using an infinite far plane"
            ));
            None
        }
        None => None,
    };
    let eye = world.w_axis.truncate();
    let forward = world.transform_vector3(Vec3::NEG_Z);
    let up = world.transform_vector3(Vec3::Y);
    if forward.length_squared() < 1e-20 || !forward.is_finite() || !eye.is_finite() {
        warnings.push(format!("{label}: camera transform is degenerate; ignored"));
        return None;
    }
    Some(Camera {
        view: look_at(eye, eye + forward, up.normalize_or(Vec3::Y)),
        fov_y: yfov,
        near: znear,
        far,
    })
}

/// The scene light from a punctual light at `world`; `None` (with a
/// warning) when its values are unusable. `label` names its node.
pub(super) fn light(
    light: &gltf::khr_lights_punctual::Light,
    world: Mat4,
    label: &str,
    warnings: &mut Warnings,
) -> Option<Light> {
    let color = Vec3::from(light.color());
    let intensity = light.intensity();
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    if !(color.is_finite() && intensity.is_finite() && intensity >= 0.0 && position.is_finite()) {
        warnings.push(format!(
            "{label}: light with non-finite or negative values; ignored"
        ));
        return None;
    }
    let range = light.range().filter(|r| r.is_finite() && *r > 0.0);
    let kind = match light.kind() {
        gltf::khr_lights_punctual::Kind::Point => LightKind::Point,
        gltf::khr_lights_punctual::Kind::Directional => LightKind::Directional,
        gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let half_pi = std::f32::consts::FRAC_PI_2;
            let outer = if outer_cone_angle.is_finite() {
                outer_cone_angle.clamp(1e-4, half_pi)
            } else {
                std::f32::consts::FRAC_PI_4
            };
            let inner = if inner_cone_angle.is_finite() {
                inner_cone_angle.clamp(0.0, outer * 0.999)
            } else {
                0.0
            };
            LightKind::Spot {
                inner_cone: inner,
                outer_cone: outer,
            }
        }
    };
    if kind != LightKind::Point && direction == Vec3::ZERO {
        warnings.push(format!(
            "{label}: light has a degenerate direction; ignored"
        ));
        return None;
    }
    Some(Light {
        kind,
        position,
        direction: if direction == Vec3::ZERO {
            Vec3::NEG_Z
        } else {
            direction
        },
        color,
        intensity,
        range,
    })
}
