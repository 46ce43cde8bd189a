//! `stx token new`: a `[[tokens]]` entry with a strong random token, different every time.

use std::process::Command;

fn new_token(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_stx"))
        .args(["token", "new"])
        .args(args)
        .output()
        .expect("stx runs");
    assert!(out.status.success(), "{out:?}");
    String::from_utf8(out.stdout).expect("text")
}

#[test]
fn a_new_token_is_256_random_bits_in_a_tokens_entry() {
    let entry = new_token(&["--name", "recovery team", "--role", "viewer"]);
    let lines: Vec<&str> = entry.lines().collect();
    assert_eq!(lines[0], "[[tokens]]");
    assert_eq!(lines[1], "name = \"recovery team\"");
    assert_eq!(lines[3], "role = \"viewer\"");
    let token = lines[2]
        .strip_prefix("token = \"")
        .and_then(|t| t.strip_suffix('"'))
        .expect("a token line");
    assert_eq!(token.len(), 64);
    assert!(token.bytes().all(|b| b.is_ascii_hexdigit()));
    let other = new_token(&[]);
    assert!(other.contains("role = \"operator\""));
    assert!(!other.contains(token), "a new token each time");
}
