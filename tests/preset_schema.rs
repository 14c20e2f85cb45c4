//! docs/presets.md documents the preset file field by field; this test holds the table to the
//! code: the same fields, the defaults a minimal file really gets, and each documented range
//! (its edges accepted, values just outside refused with an error naming the field).

use nimbus::Weather;
use toml::Value;

struct Row {
    field: String,
    range: String,
    default: String,
}

fn rows() -> Vec<Row> {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/presets.md"))
        .expect("docs/presets.md");
    doc.lines()
        .filter(|l| l.starts_with("| `"))
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
            assert_eq!(cells.len(), 6, "row {l:?} needs 6 cells");
            Row {
                field: cells[0].trim_matches('`').to_string(),
                range: cells[3].to_string(),
                default: cells[4].to_string(),
            }
        })
        .collect()
}

/// A file that sets one field to its own default: everything else is defaulted.
const MINIMAL: &str = "[clouds]\ncoverage = 0.4\n";

fn minimal() -> Value {
    let w = Weather::from_toml(MINIMAL, "<minimal>").unwrap();
    toml::from_str(&w.to_toml()).unwrap()
}

/// Leaf paths of a preset document; `map.layers[]` stands for every layer table.
fn leaves(v: &Value, prefix: &str, out: &mut Vec<String>) {
    match v {
        Value::Table(t) => {
            for (k, v) in t {
                let path = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                leaves(v, &path, out);
            }
        }
        Value::Array(a) if a.first().is_some_and(Value::is_table) => {
            leaves(&a[0], &format!("{prefix}[]"), out)
        }
        _ => out.push(prefix.to_string()),
    }
}

fn slot<'a>(doc: &'a mut Value, path: &str) -> &'a mut Value {
    let mut v = doc;
    for part in path.split('.') {
        v = match part.strip_suffix("[]") {
            Some(name) => &mut v[name][0],
            None => &mut v[part],
        };
    }
    v
}

fn close(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| close(p, q))
        }
        _ => match (
            a.as_float().or(a.as_integer().map(|i| i as f64)),
            b.as_float().or(b.as_integer().map(|i| i as f64)),
        ) {
            (Some(x), Some(y)) => (x - y).abs() <= 1e-5 * (1.0 + x.abs()),
            _ => a == b,
        },
    }
}

/// Parses the document with `path` set to `value`: Ok, or the error's text.
fn with(path: &str, value: Value) -> Result<(), String> {
    let mut doc = minimal();
    *slot(&mut doc, path) = value;
    Weather::from_toml(&toml::to_string(&doc).unwrap(), "<edited>")
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn number_like(template: &Value, x: f64) -> Value {
    if template.is_integer() {
        Value::Integer(x as i64)
    } else {
        Value::Float(x)
    }
}

#[test]
fn documented_fields_are_the_code_fields() {
    let mut code = Vec::new();
    leaves(&minimal(), "", &mut code);
    code.sort();
    let mut documented: Vec<String> = rows().into_iter().map(|r| r.field).collect();
    documented.sort();
    assert_eq!(documented, code, "docs/presets.md vs the preset struct");
}

#[test]
fn documented_defaults_are_what_a_minimal_file_gets() {
    let mut doc = minimal();
    for r in rows() {
        let want: Value = toml::from_str::<toml::Table>(&format!("v = {}", r.default))
            .unwrap_or_else(|e| panic!("{}: default {:?}: {e}", r.field, r.default))["v"]
            .clone();
        let got = slot(&mut doc, &r.field).clone();
        assert!(
            close(&got, &want),
            "{}: documented {want}, code {got}",
            r.field
        );
    }
}

#[test]
fn documented_ranges_hold_at_their_edges() {
    let mut checked = 0;
    for r in rows() {
        let leaf = r.field.rsplit('.').next().unwrap().to_string();
        let template = slot(&mut minimal(), &r.field).clone();
        let refuse = |v: Value| {
            let e =
                with(&r.field, v.clone()).expect_err(&format!("{} = {v} must be refused", r.field));
            assert!(
                e.contains(&leaf),
                "{}: the error {e:?} does not name the field",
                r.field
            );
        };
        let accept = |v: Value| {
            with(&r.field, v.clone())
                .unwrap_or_else(|e| panic!("{} = {v} must be accepted: {e}", r.field))
        };
        let range = r.range.as_str();
        if let Some(inner) = range.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
            let (lo, hi) = inner.split_once(',').unwrap();
            let (lo, hi): (f64, f64) = (lo.trim().parse().unwrap(), hi.trim().parse().unwrap());
            let step = if template.is_integer() { 1.0 } else { 1e-3 };
            accept(number_like(&template, lo));
            accept(number_like(&template, hi));
            refuse(number_like(&template, lo - step));
            refuse(number_like(&template, hi + step));
        } else if range.starts_with(">= 0") {
            accept(number_like(&template, 0.0));
            refuse(Value::Float(-1e-3));
        } else if let Some(other) = range.strip_prefix("> `").and_then(|s| s.strip_suffix('`')) {
            // Above another field: its value is the edge (the error may name either field).
            let edge = slot(&mut minimal(), other).as_float().unwrap();
            accept(Value::Float(edge + 1.0));
            with(&r.field, Value::Float(edge))
                .expect_err(&format!("{} = {edge} must be refused", r.field));
        } else if range == "> 0" {
            accept(Value::Float(1e-3));
            refuse(Value::Float(0.0));
        } else if range == "each >= 0" {
            accept(Value::Array(vec![Value::Float(0.0); 3]));
            refuse(Value::Array(vec![
                Value::Float(-0.1),
                Value::Float(0.0),
                Value::Float(0.0),
            ]));
        } else if range == "finite" {
            let nan = match &template {
                Value::Array(a) => Value::Array(vec![Value::Float(f64::NAN); a.len()]),
                _ => Value::Float(f64::NAN),
            };
            refuse(nan);
        } else {
            assert!(
                range.starts_with("any"),
                "{}: unknown range {range:?}",
                r.field
            );
            continue;
        }
        checked += 1;
    }
    assert!(checked >= 20, "only {checked} ranges checked");
}
