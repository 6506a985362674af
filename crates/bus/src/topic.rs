//! Typed topic handles and the JSON codec every transport uses.

use crate::transport::BusError;
use schemars::JsonSchema;
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::marker::PhantomData;

/// A type that can travel on the bus: serializable, shareable between threads, owned.
pub trait Message: Serialize + DeserializeOwned + Send + Sync + 'static {}

impl<T: Serialize + DeserializeOwned + Send + Sync + 'static> Message for T {}

/// A topic name bound to its message type, so that publishing or reading the wrong type is a
/// compile error rather than a decode failure at run time.
pub struct Topic<T> {
    name: &'static str,
    message: PhantomData<fn() -> T>,
}

impl<T> Clone for Topic<T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for Topic<T> {}

impl<T> std::fmt::Debug for Topic<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Topic({} : {})", self.name, short_type_name::<T>())
    }
}

impl<T> Topic<T> {
    /// A topic called `name` (ROS style: `/layer/what`, lower-case words and `_`).
    pub const fn new(name: &'static str) -> Self {
        Self { name, message: PhantomData }
    }

    /// The topic name.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// The message type's name without its module path (a schema name for recorders).
    pub fn type_name(&self) -> &'static str {
        short_type_name::<T>()
    }

    /// The message type's JSON Schema.
    pub fn schema(&self) -> serde_json::Value
    where
        T: JsonSchema,
    {
        crate::schema::schema_of::<T>()
    }
}

/// `std::any::type_name` without the module path of the outer type.
fn short_type_name<T>() -> &'static str {
    let full = std::any::type_name::<T>();
    let outer = full.split('<').next().unwrap_or(full);
    let start = outer.rfind("::").map_or(0, |i| i + 2);
    &full[start..]
}

/// Checks a ROS-style topic name: `/` then `/`-separated non-empty words of `[a-z0-9_]`.
pub fn check_topic_name(name: &str) -> Result<(), BusError> {
    let bad = |why| Err(BusError::BadTopic { name: name.to_string(), why });
    let Some(rest) = name.strip_prefix('/') else {
        return bad("must start with `/`");
    };
    if rest.split('/').any(str::is_empty) {
        return bad("empty segment");
    }
    if !rest.chars().all(|c| c == '/' || c == '_' || c.is_ascii_lowercase() || c.is_ascii_digit()) {
        return bad("only lower-case letters, digits, `_` and `/` are allowed");
    }
    Ok(())
}

/// Encodes a message as JSON.
pub fn encode<T: Message>(topic: &Topic<T>, message: &T) -> Result<Vec<u8>, BusError> {
    serde_json::to_vec(message).map_err(|e| BusError::Codec {
        topic: topic.name().to_string(),
        action: "encode",
        type_name: topic.type_name().to_string(),
        message: e.to_string(),
    })
}

/// Decodes a JSON message.
pub fn decode<T: Message>(topic: &Topic<T>, payload: &[u8]) -> Result<T, BusError> {
    serde_json::from_slice(payload).map_err(|e| BusError::Codec {
        topic: topic.name().to_string(),
        action: "decode",
        type_name: topic.type_name().to_string(),
        message: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_ros_style() {
        assert!(check_topic_name("/platform/frame").is_ok());
        assert!(check_topic_name("/a_1").is_ok());
        for bad in ["", "/", "platform", "/a//b", "/a/", "/Upper", "/sp ace", "/dash-ed"] {
            assert!(check_topic_name(bad).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn codec_round_trips_floats_exactly() {
        let topic: Topic<Vec<f64>> = Topic::new("/x");
        let values = vec![0.1, 1.0 / 3.0, -2.5e-300, f64::MAX, 5e-324, 0.1 + 0.2, 1e23];
        let back = decode(&topic, &encode(&topic, &values).unwrap()).unwrap();
        assert_eq!(
            back.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            values.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(topic.type_name(), "Vec<f64>");
        let wrong: Topic<String> = Topic::new("/x");
        let err = decode(&wrong, b"[1.0]").unwrap_err().to_string();
        assert!(err.contains("/x") && err.contains("decode") && err.contains("String"), "{err}");
    }
}
