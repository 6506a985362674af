//! Camera models from product metadata: the `GEOMETRIC_CAMERA_MODEL` group of a PDS3 label
//! (MSL, MER, Mars 2020 EDRs) and the Mars 2020 raw-image JSON metadata.
//!
//! PDS3: MODEL_TYPE names the model, MODEL_COMPONENT_1..6 are C, A, H, V, O, R (vectors),
//! MODEL_COMPONENT_7 is E, MODEL_COMPONENT_8 the CAHVORE type (1, 2, 3) and
//! MODEL_COMPONENT_9 its parameter; the image size comes from the IMAGE object's LINE_SAMPLES
//! and LINES.
//!
//! Mars 2020 raw-image JSON (one image record of the public raw-images API): the model is the
//! string `camera.camera_model_component_list` = "(c1,c2,c3);(a1,a2,a3);(h..);(v..);(o..);
//! (r..);(e..);type;parameter" (as many groups as the model has), its type
//! `camera.camera_model_type` (both also accepted at the top level of the record, as older API
//! records have them), and the image size `extended.dimension` = "(width,height)". The
//! API's models are already expressed for the returned image (their image centre lies at the
//! middle of `dimension`), so no subframe or downsampling correction is applied.
//!
//! A and O are normalised on reading (they are printed to six digits; the unprojection assumes
//! unit vectors); vectors further than 1 % from unit length are rejected.

use nalgebra::Vector3;
use rovernav_terrain::io::{Pds3Block, Pds3Label};
use serde_json::Value;
use thiserror::Error;

use super::{AnyCamera, Cahv, Cahvor, Cahvore, CahvoreType};

/// Why a camera model could not be read. Every variant names the source and the field.
#[derive(Debug, Error, PartialEq)]
pub enum CameraReadError {
    /// A required field is absent.
    #[error("{origin}: field {field} missing")]
    Missing {
        /// The file or document read.
        origin: String,
        /// The field.
        field: String,
    },
    /// A field is present but unusable.
    #[error("{origin}: field {field}: {reason}")]
    Invalid {
        /// The file or document read.
        origin: String,
        /// The field.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The document is not JSON.
    #[error("{origin}: not JSON: {reason}")]
    Json {
        /// The document read.
        origin: String,
        /// The parser's message.
        reason: String,
    },
}

/// One component of a model: a 3-vector or a scalar.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Component {
    Vector(Vector3<f64>),
    Scalar(f64),
}

/// Builds a model from its type name, components in label order and image size.
fn build(
    origin: &str,
    type_field: &str,
    type_name: &str,
    component_field: &dyn Fn(usize) -> String,
    components: &[Option<Component>],
    width: usize,
    height: usize,
) -> Result<AnyCamera, CameraReadError> {
    let missing = |i: usize| CameraReadError::Missing { origin: origin.into(), field: component_field(i) };
    let invalid = |i: usize, reason: &str| CameraReadError::Invalid {
        origin: origin.into(),
        field: component_field(i),
        reason: reason.into(),
    };
    let vector = |i: usize| -> Result<Vector3<f64>, CameraReadError> {
        match components.get(i - 1).copied().flatten() {
            Some(Component::Vector(v)) if v.iter().all(|x| x.is_finite()) => Ok(v),
            Some(_) => Err(invalid(i, "expected three finite numbers")),
            None => Err(missing(i)),
        }
    };
    let scalar = |i: usize| -> Result<f64, CameraReadError> {
        match components.get(i - 1).copied().flatten() {
            Some(Component::Scalar(x)) if x.is_finite() => Ok(x),
            Some(_) => Err(invalid(i, "expected one finite number")),
            None => Err(missing(i)),
        }
    };
    let unit = |i: usize| -> Result<Vector3<f64>, CameraReadError> {
        let v = vector(i)?;
        let n = v.norm();
        if (n - 1.0).abs() > 1e-2 {
            return Err(invalid(i, &format!("expected a unit vector, its length is {n}")));
        }
        Ok(v / n)
    };
    let (c, a, h, v) = (vector(1)?, unit(2)?, vector(3)?, vector(4)?);
    if a.cross(&h).norm() < 1e-9 || a.cross(&v).norm() < 1e-9 || h.cross(&v).dot(&a).abs() < 1e-9 {
        return Err(invalid(3, "H and V must span the image plane with A"));
    }
    let linear = Cahv { c, a, h, v, width, height };
    match type_name.trim().to_ascii_uppercase().as_str() {
        "CAHV" => Ok(AnyCamera::Cahv(linear)),
        "CAHVOR" => Ok(AnyCamera::Cahvor(Cahvor::new(linear, unit(5)?, vector(6)?))),
        "CAHVORE" => {
            let (code, parameter) = (scalar(8)?, scalar(9)?);
            let kind = CahvoreType::from_code(code, parameter)
                .ok_or_else(|| invalid(8, &format!("CAHVORE type {code} is not 1, 2 or 3")))?;
            Ok(AnyCamera::Cahvore(Cahvore::new(linear, unit(5)?, vector(6)?, vector(7)?, kind)))
        }
        other => Err(CameraReadError::Invalid {
            origin: origin.into(),
            field: type_field.into(),
            reason: format!("unsupported model type {other:?} (expected CAHV, CAHVOR or CAHVORE)"),
        }),
    }
}

/// The camera model of a PDS3 label's `GEOMETRIC_CAMERA_MODEL` group, sized by its IMAGE.
pub fn from_pds3_label(label: &Pds3Label) -> Result<AnyCamera, CameraReadError> {
    let origin = label.file.display().to_string();
    let group_name = "GEOMETRIC_CAMERA_MODEL";
    let group = label
        .block(group_name)
        .ok_or_else(|| CameraReadError::Missing { origin: origin.clone(), field: group_name.into() })?;
    let type_field = format!("{group_name}.MODEL_TYPE");
    let type_name = group
        .get_str("MODEL_TYPE")
        .ok_or_else(|| CameraReadError::Missing { origin: origin.clone(), field: type_field.clone() })?;
    let components: Vec<Option<Component>> = (1..=9)
        .map(|i| {
            let values = group.get(&format!("MODEL_COMPONENT_{i}"))?.as_f64_vec();
            Some(match values.as_deref() {
                Some([x]) => Component::Scalar(*x),
                Some([x, y, z]) => Component::Vector(Vector3::new(*x, *y, *z)),
                _ => Component::Scalar(f64::NAN),
            })
        })
        .collect();
    let image = label.block("IMAGE");
    let size = |key: &str| image_count(image, &origin, key);
    let (width, height) = (size("LINE_SAMPLES")?, size("LINES")?);
    let field = |i: usize| format!("{group_name}.MODEL_COMPONENT_{i}");
    build(&origin, &type_field, type_name, &field, &components, width, height)
}

fn image_count(image: Option<&Pds3Block>, origin: &str, key: &str) -> Result<usize, CameraReadError> {
    let field = format!("IMAGE.{key}");
    let value = image
        .and_then(|b| b.get_f64(key))
        .ok_or_else(|| CameraReadError::Missing { origin: origin.into(), field: field.clone() })?;
    if value >= 1.0 && value.fract() == 0.0 && value < 1e6 {
        Ok(value as usize)
    } else {
        Err(CameraReadError::Invalid {
            origin: origin.into(),
            field,
            reason: format!("{value} is not a size"),
        })
    }
}

/// The camera model of one Mars 2020 raw-image JSON record given as text; `origin` names the
/// document in errors.
pub fn from_m2020_json_str(text: &str, origin: &str) -> Result<AnyCamera, CameraReadError> {
    let value: Value = serde_json::from_str(text)
        .map_err(|e| CameraReadError::Json { origin: origin.into(), reason: e.to_string() })?;
    from_m2020_json(&value, origin)
}

/// The camera model of one Mars 2020 raw-image JSON record (see the module documentation).
pub fn from_m2020_json(record: &Value, origin: &str) -> Result<AnyCamera, CameraReadError> {
    let missing = |field: &str| CameraReadError::Missing { origin: origin.into(), field: field.into() };
    let invalid = |field: &str, reason: String| CameraReadError::Invalid {
        origin: origin.into(),
        field: field.into(),
        reason,
    };
    let text = |path: &[&str]| -> Result<&str, CameraReadError> {
        let field = path.join(".");
        let mut v = record;
        for key in path {
            v = v.get(key).ok_or_else(|| missing(&field))?;
        }
        v.as_str().ok_or_else(|| invalid(&field, "expected a string".into()))
    };
    let list_field = "camera.camera_model_component_list";
    let type_field = "camera.camera_model_type";
    // Records of the older API flatten the camera fields to the top level.
    let camera_text = |key: &str| match text(&["camera", key]) {
        Err(e @ CameraReadError::Missing { .. }) => text(&[key]).map_err(|_| e),
        other => other,
    };
    let list = camera_text("camera_model_component_list")?;
    let type_name = camera_text("camera_model_type")?;
    let dimension = text(&["extended", "dimension"])?;
    let dims = parse_tuple(dimension)
        .filter(|d| d.len() == 2 && d.iter().all(|x| *x >= 1.0 && x.fract() == 0.0 && *x < 1e6));
    let dims = dims
        .ok_or_else(|| invalid("extended.dimension", format!("{dimension:?} is not \"(width,height)\"")))?;
    let components: Vec<Option<Component>> = list
        .split(';')
        .map(|part| {
            let part = part.trim();
            Some(match parse_tuple(part).as_deref() {
                Some([x, y, z]) => Component::Vector(Vector3::new(*x, *y, *z)),
                Some(_) => Component::Scalar(f64::NAN),
                None => Component::Scalar(part.parse::<f64>().unwrap_or(f64::NAN)),
            })
        })
        .collect();
    let field = |i: usize| format!("{list_field}[{}]", i - 1);
    build(origin, type_field, type_name, &field, &components, dims[0] as usize, dims[1] as usize)
}

/// The numbers of a parenthesised, comma-separated tuple such as "(1.5,-2,3e2)".
fn parse_tuple(text: &str) -> Option<Vec<f64>> {
    let inner = text.trim().strip_prefix('(')?.strip_suffix(')')?;
    inner.split(',').map(|x| x.trim().parse::<f64>().ok().filter(|v| v.is_finite())).collect()
}
