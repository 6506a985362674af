//! Hand-written JSON Schemas (draft 2020-12 subset) for the telemetry messages, and a checker
//! for that subset.
//!
//! Foxglove and other MCAP tools read `jsonschema` schemas to list a topic's fields; a derive
//! crate would cost a proc-macro build for a dozen small schemas. Every object schema lists all
//! its properties as required and forbids others, so the checker (used by the tests on real
//! messages) catches any drift between a message struct and its schema.

use serde_json::{Map, Value, json};

/// A number (JSON has no NaN: fields that may be NaN are `nullable`).
pub fn number(description: &str) -> Value {
    json!({ "type": "number", "description": description })
}

/// An integer.
pub fn integer(description: &str) -> Value {
    json!({ "type": "integer", "description": description })
}

/// A boolean.
pub fn boolean(description: &str) -> Value {
    json!({ "type": "boolean", "description": description })
}

/// A string.
pub fn string(description: &str) -> Value {
    json!({ "type": "string", "description": description })
}

/// A string with a fixed set of values.
pub fn enumeration(description: &str, values: &[&str]) -> Value {
    json!({ "type": "string", "enum": values, "description": description })
}

/// Base64 bytes, as Foxglove's JSON schemas mark them.
pub fn bytes(description: &str) -> Value {
    json!({ "type": "string", "contentEncoding": "base64", "description": description })
}

/// The schema, or null.
pub fn nullable(mut schema: Value) -> Value {
    if let Some(t) = schema.get("type").cloned() {
        schema["type"] = json!([t, "null"]);
    }
    schema
}

/// An array of items.
pub fn array(description: &str, items: Value) -> Value {
    json!({ "type": "array", "items": items, "description": description })
}

/// An array of exactly `n` items.
pub fn fixed_array(description: &str, items: Value, n: usize) -> Value {
    json!({ "type": "array", "items": items, "minItems": n, "maxItems": n, "description": description })
}

/// An object whose properties are all required and which allows no others.
pub fn object(description: &str, properties: &[(&str, Value)]) -> Value {
    let props: Map<String, Value> = properties.iter().map(|(k, v)| (k.to_string(), v.clone())).collect();
    let required: Vec<&str> = properties.iter().map(|(k, _)| *k).collect();
    json!({
        "type": "object",
        "description": description,
        "properties": props,
        "required": required,
        "additionalProperties": false,
    })
}

/// A top-level message schema: an object with a title and the JSON Schema dialect.
pub fn message(title: &str, description: &str, properties: &[(&str, Value)]) -> Value {
    let mut schema = object(description, properties);
    schema["$schema"] = json!("https://json-schema.org/draft/2020-12/schema");
    schema["title"] = json!(title);
    schema
}

/// Checks a value against a schema built by this module (type, enum, properties, required,
/// additionalProperties, items, min/maxItems, base64 content); the error names the JSON path.
pub fn check(schema: &Value, value: &Value) -> Result<(), String> {
    check_at(schema, value, "$")
}

fn check_at(schema: &Value, value: &Value, path: &str) -> Result<(), String> {
    if let Some(t) = schema.get("type") {
        let types: Vec<&str> = match t {
            Value::Array(ts) => ts.iter().filter_map(Value::as_str).collect(),
            other => other.as_str().into_iter().collect(),
        };
        if !types.iter().any(|t| type_matches(t, value)) {
            return Err(format!("{path}: expected {}, found {value}", types.join(" or ")));
        }
    }
    if value.is_null() {
        return Ok(());
    }
    if let (Some(allowed), Some(s)) = (schema.get("enum").and_then(Value::as_array), value.as_str())
        && !allowed.iter().any(|a| a.as_str() == Some(s))
    {
        return Err(format!("{path}: `{s}` is not one of {}", Value::Array(allowed.clone())));
    }
    if schema.get("contentEncoding").and_then(Value::as_str) == Some("base64")
        && let Some(s) = value.as_str()
    {
        crate::base64::decode(s).map_err(|e| format!("{path}: {e}"))?;
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
            match props.and_then(|p| p.get(k)) {
                Some(sub) => check_at(sub, v, &format!("{path}.{k}"))?,
                None if schema.get("additionalProperties") == Some(&Value::Bool(false)) => {
                    return Err(format!("{path}: field `{k}` is not in the schema"));
                }
                None => {}
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
        if let Some(item_schema) = schema.get("items") {
            for (i, v) in items.iter().enumerate() {
                check_at(item_schema, v, &format!("{path}[{i}]"))?;
            }
        }
    }
    Ok(())
}

fn type_matches(t: &str, v: &Value) -> bool {
    match t {
        "null" => v.is_null(),
        "boolean" => v.is_boolean(),
        "integer" => v.is_u64() || v.is_i64(),
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

    fn sample_schema() -> Value {
        message(
            "test.Sample",
            "a sample",
            &[
                ("n", integer("count")),
                ("x", nullable(number("maybe NaN"))),
                ("kind", enumeration("which", &["a", "b"])),
                ("data", bytes("payload")),
                ("xyz", fixed_array("vector", number("component"), 3)),
                ("inner", object("nested", &[("flag", boolean("a flag"))])),
            ],
        )
    }

    #[test]
    fn a_conforming_value_passes() {
        let v = json!({"n": 3, "x": null, "kind": "a", "data": "Zm9v", "xyz": [1, 2.5, 3], "inner": {"flag": true}});
        check(&sample_schema(), &v).unwrap();
    }

    #[test]
    fn every_kind_of_violation_is_named_with_its_path() {
        let ok =
            json!({"n": 3, "x": 1.0, "kind": "a", "data": "Zm9v", "xyz": [1, 2, 3], "inner": {"flag": true}});
        let cases: [(&str, Value, &str); 7] = [
            ("n", json!(1.5), "$.n: expected integer"),
            ("kind", json!("c"), "$.kind: `c` is not one of"),
            ("data", json!("Zm9"), "$.data: bad base64"),
            ("xyz", json!([1, 2]), "$.xyz: array of 2 items"),
            ("xyz", json!([1, "2", 3]), "$.xyz[1]: expected number"),
            ("inner", json!({"flag": true, "extra": 1}), "$.inner: field `extra` is not in the schema"),
            ("inner", json!({}), "$.inner: missing field `flag`"),
        ];
        for (field, bad, expected) in cases {
            let mut v = ok.clone();
            v[field] = bad;
            let err = check(&sample_schema(), &v).unwrap_err();
            assert!(err.starts_with(expected), "{field}: {err}");
        }
    }
}
