//! The console's access token: generated at start (as Jupyter does) or read from a file, and
//! checked on every request.
//!
//! A client presents it as `Authorization: Bearer TOKEN` or `?token=TOKEN`; the comparison takes
//! the same time whatever the first differing byte, so response timing does not reveal it.

use std::io::Read;
use std::path::Path;

/// Bytes of randomness in a generated token (rendered as twice as many hex digits).
const TOKEN_BYTES: usize = 24;

/// Longest token accepted from a file.
const MAX_TOKEN_LEN: usize = 256;

/// A fresh random token: 48 hex digits from the operating system's random source.
pub fn generate_token() -> Result<String, String> {
    let mut bytes = [0u8; TOKEN_BYTES];
    std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut bytes))
        .map_err(|e| format!("/dev/urandom: cannot read random bytes for the access token: {e}"))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// The token in a file: its first line, trimmed; refused when empty, longer than 256 bytes or not
/// URL-safe (letters, digits, `-`, `_`, `.`, `~`), so that it can be passed as `?token=`.
pub fn read_token_file(path: &Path) -> Result<String, String> {
    let shown = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{shown}: cannot read the token: {e}"))?;
    let token = text.lines().next().unwrap_or("").trim();
    if token.is_empty() {
        return Err(format!("{shown}: the token file is empty"));
    }
    if token.len() > MAX_TOKEN_LEN {
        return Err(format!("{shown}: the token is longer than {MAX_TOKEN_LEN} bytes"));
    }
    if let Some(c) = token.chars().find(|c| !is_url_safe(*c)) {
        return Err(format!("{shown}: the token holds {c:?}; use letters, digits, '-', '_', '.' or '~'"));
    }
    Ok(token.to_string())
}

fn is_url_safe(c: char) -> bool {
    c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.' | '~')
}

/// Whether `given` equals `token`, in time independent of where they differ.
pub fn same_token(given: &str, token: &str) -> bool {
    let (a, b) = (given.as_bytes(), token.as_bytes());
    let mut diff = (a.len() != b.len()) as u8;
    for (i, &t) in b.iter().enumerate() {
        diff |= a.get(i).copied().unwrap_or(0) ^ t;
    }
    diff == 0
}

/// The token a request presents: the `Authorization: Bearer` header's, else the query's `token`.
pub fn presented_token<'a>(authorization: Option<&'a str>, query: Option<&'a str>) -> Option<&'a str> {
    if let Some(bearer) = authorization.and_then(|h| h.strip_prefix("Bearer ")) {
        return Some(bearer.trim());
    }
    query?.split('&').find_map(|pair| pair.strip_prefix("token="))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_tokens_are_long_hex_and_differ() {
        let a = generate_token().unwrap();
        let b = generate_token().unwrap();
        assert_eq!(a.len(), 2 * TOKEN_BYTES);
        assert!(a.chars().all(|c| c.is_ascii_hexdigit()));
        assert_ne!(a, b);
    }

    #[test]
    fn comparison_needs_every_byte_and_the_length() {
        assert!(same_token("abc", "abc"));
        assert!(!same_token("abd", "abc"));
        assert!(!same_token("ab", "abc"));
        assert!(!same_token("abcd", "abc"));
        assert!(!same_token("", "abc"));
    }

    #[test]
    fn the_header_wins_over_the_query() {
        assert_eq!(presented_token(Some("Bearer x1"), Some("token=y")), Some("x1"));
        assert_eq!(presented_token(None, Some("a=1&token=y")), Some("y"));
        assert_eq!(presented_token(Some("Basic zz"), Some("a=1")), None);
        assert_eq!(presented_token(None, None), None);
    }

    #[test]
    fn token_files_are_checked() {
        let dir = std::env::temp_dir().join(format!("rovernav-auth-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("t");
        std::fs::write(&file, "  s3cret-token_1\nignored\n").unwrap();
        assert_eq!(read_token_file(&file).unwrap(), "s3cret-token_1");
        std::fs::write(&file, "\n").unwrap();
        assert!(read_token_file(&file).unwrap_err().contains("empty"));
        std::fs::write(&file, "a b").unwrap();
        assert!(read_token_file(&file).unwrap_err().contains("' '"));
        std::fs::remove_dir_all(&dir).ok();
        assert!(read_token_file(&dir.join("missing")).unwrap_err().contains("cannot read"));
    }
}
