//! JSON Schemas of the message types, derived with `schemars` (draft 2020-12), and a checker for
//! the subset of the dialect those schemas use.
//!
//! One schema source serves the bus and the MCAP log (Foxglove lists a channel's fields from
//! it). The checker validates a serialized message against its schema (the tests run it on every
//! message type), so that a codec written by hand for a field (base64 points, NaN as `null`)
//! cannot drift from what the schema says.
//!
//! Supported keywords: `type` (one or a list), `enum`, `const`, `$ref` (to `#/$defs/NAME`),
//! `oneOf`, `anyOf`, `allOf`, `properties`, `required`, `additionalProperties`, `items`,
//! `prefixItems`, `minItems`, `maxItems`, `minimum`, `maximum` and `contentEncoding: base64`.
//! Others (`format`, `description`, `title`) are annotations here.

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD;
use schemars::JsonSchema;
use serde_json::Value;

/// The JSON Schema of a message type, titled with the type's name.
pub fn schema_of<T: JsonSchema>() -> Value {
    schemars::schema_for!(T).to_value()
}

/// The JSON Schema of a message type under a given title (a channel's schema name).
pub fn titled_schema_of<T: JsonSchema>(title: &str) -> Value {
    let mut schema = schema_of::<T>();
    if let Some(obj) = schema.as_object_mut() {
        obj.insert("title".into(), Value::String(title.into()));
    }
    schema
}

/// Checks a value against a schema; the error names the JSON path of the first violation.
pub fn check(schema: &Value, value: &Value) -> Result<(), String> {
    check_at(schema, schema, value, "$")
}

fn resolve<'a>(root: &'a Value, reference: &str, path: &str) -> Result<&'a Value, String> {
    reference
        .strip_prefix("#/$defs/")
        .and_then(|name| root.get("$defs").and_then(|d| d.get(name)))
        .or_else(|| (reference == "#").then_some(root))
        .ok_or_else(|| format!("{path}: unresolved schema reference `{reference}`"))
}

fn check_at(root: &Value, schema: &Value, value: &Value, path: &str) -> Result<(), String> {
    let schema = match schema {
        Value::Bool(true) => return Ok(()),
        Value::Bool(false) => return Err(format!("{path}: no value is allowed here")),
        s => s,
    };
    if let Some(r) = schema.get("$ref").and_then(Value::as_str) {
        check_at(root, resolve(root, r, path)?, value, path)?;
    }
    for sub in schema.get("allOf").and_then(Value::as_array).into_iter().flatten() {
        check_at(root, sub, value, path)?;
    }
    for (key, exactly_one) in [("oneOf", true), ("anyOf", false)] {
        if let Some(subs) = schema.get(key).and_then(Value::as_array) {
            let results: Vec<Result<(), String>> =
                subs.iter().map(|s| check_at(root, s, value, path)).collect();
            let passed = results.iter().filter(|r| r.is_ok()).count();
            if passed == 0 || (exactly_one && passed > 1) {
                let why: Vec<String> = results.into_iter().filter_map(Result::err).collect();
                return Err(format!("{path}: {passed} of the {key} alternatives match ({})", why.join("; ")));
            }
        }
    }
    if let Some(t) = schema.get("type") {
        let types: Vec<&str> = match t {
            Value::Array(ts) => ts.iter().filter_map(Value::as_str).collect(),
            other => other.as_str().into_iter().collect(),
        };
        if !types.iter().any(|t| type_matches(t, value)) {
            return Err(format!("{path}: expected {}, found {}", types.join(" or "), short(value)));
        }
    }
    if let Some(c) = schema.get("const")
        && c != value
    {
        return Err(format!("{path}: expected {c}, found {}", short(value)));
    }
    if let Some(allowed) = schema.get("enum").and_then(Value::as_array)
        && !allowed.contains(value)
    {
        return Err(format!("{path}: {} is not one of {}", short(value), Value::Array(allowed.clone())));
    }
    if let Some(x) = value.as_f64() {
        let bound = |key: &str| schema.get(key).and_then(Value::as_f64);
        if bound("minimum").is_some_and(|m| x < m) || bound("maximum").is_some_and(|m| x > m) {
            return Err(format!("{path}: {x} is outside the schema's bounds"));
        }
    }
    if schema.get("contentEncoding").and_then(Value::as_str) == Some("base64")
        && let Some(s) = value.as_str()
    {
        STANDARD.decode(s).map_err(|e| format!("{path}: bad base64 ({e})"))?;
    }
    if let Some(obj) = value.as_object() {
        let props = schema.get("properties").and_then(Value::as_object);
        for name in schema.get("required").and_then(Value::as_array).into_iter().flatten() {
            let name = name.as_str().unwrap_or_default();
            if !obj.contains_key(name) {
                return Err(format!("{path}: missing field `{name}`"));
            }
        }
        for (k, v) in obj {
            let sub_path = format!("{path}.{k}");
            match (props.and_then(|p| p.get(k)), schema.get("additionalProperties")) {
                (Some(sub), _) => check_at(root, sub, v, &sub_path)?,
                (None, Some(Value::Bool(false))) => {
                    return Err(format!("{path}: field `{k}` is not in the schema"));
                }
                (None, Some(extra)) => check_at(root, extra, v, &sub_path)?,
                (None, None) => {}
            }
        }
    }
    if let Some(items) = value.as_array() {
        let bound = |key: &str| schema.get(key).and_then(Value::as_u64).map(|n| n as usize);
        if bound("minItems").is_some_and(|n| items.len() < n)
            || bound("maxItems").is_some_and(|n| items.len() > n)
        {
            return Err(format!("{path}: array of {} items is outside the schema's bounds", items.len()));
        }
        let prefix = schema.get("prefixItems").and_then(Value::as_array).map_or(&[][..], Vec::as_slice);
        for (i, v) in items.iter().enumerate() {
            let sub = prefix.get(i).or_else(|| schema.get("items"));
            if let Some(sub) = sub {
                check_at(root, sub, v, &format!("{path}[{i}]"))?;
            }
        }
    }
    Ok(())
}

fn short(v: &Value) -> String {
    let text = v.to_string();
    if text.len() > 60 { format!("{}...", &text[..text.floor_char_boundary(57)]) } else { text }
}

fn type_matches(t: &str, v: &Value) -> bool {
    match t {
        "null" => v.is_null(),
        "boolean" => v.is_boolean(),
        "integer" => v.is_u64() || v.is_i64() || v.as_f64().is_some_and(|x| x.fract() == 0.0),
        "number" => v.is_number(),
        "string" => v.is_string(),
        "array" => v.is_array(),
        "object" => v.is_object(),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;
    use serde_json::json;

    /// A sample exercising each construct the derive emits.
    #[derive(Serialize, JsonSchema)]
    #[serde(rename_all = "snake_case")]
    enum Shape {
        Dot,
        Circle { r: f64 },
        Pair(u8, String),
    }

    #[derive(Serialize, JsonSchema)]
    struct Sample {
        n: u32,
        maybe: Option<f64>,
        xyz: [f64; 3],
        shapes: Vec<Shape>,
        #[schemars(with = "String", extend("contentEncoding" = "base64"))]
        data: String,
    }

    fn sample() -> Value {
        serde_json::to_value(Sample {
            n: 3,
            maybe: None,
            xyz: [1.0, 2.5, 3.0],
            shapes: vec![Shape::Dot, Shape::Circle { r: 1.0 }, Shape::Pair(7, "a".into())],
            data: "Zm9v".into(),
        })
        .unwrap()
    }

    #[test]
    fn a_serialized_value_fits_its_derived_schema() {
        check(&schema_of::<Sample>(), &sample()).unwrap();
    }

    #[test]
    fn every_kind_of_violation_is_named_with_its_path() {
        let schema = schema_of::<Sample>();
        let cases: [(&str, Value, &str); 8] = [
            ("n", json!(1.5), "$.n: expected integer"),
            ("n", json!(-1), "$.n: -1 is outside"),
            ("maybe", json!("x"), "$.maybe: expected number or null"),
            ("xyz", json!([1, 2]), "$.xyz: array of 2 items"),
            ("xyz", json!([1, "2", 3]), "$.xyz[1]: expected number"),
            ("shapes", json!(["square"]), "$.shapes[0]: 0 of the oneOf alternatives"),
            ("shapes", json!([{"pair": [300, "a"]}]), "$.shapes[0]: 0 of the oneOf"),
            ("data", json!("Zm9"), "$.data: bad base64"),
        ];
        for (field, bad, expected) in cases {
            let mut v = sample();
            v[field] = bad;
            let err = check(&schema, &v).unwrap_err();
            assert!(err.starts_with(expected), "{field}: {err}");
        }
        let mut v = sample();
        v.as_object_mut().unwrap().remove("xyz");
        assert_eq!(check(&schema, &v).unwrap_err(), "$: missing field `xyz`");
    }

    #[test]
    fn a_title_names_the_channel_schema() {
        assert_eq!(titled_schema_of::<Sample>("rovernav.Sample")["title"], "rovernav.Sample");
        assert_eq!(schema_of::<Sample>()["title"], "Sample");
    }
}
