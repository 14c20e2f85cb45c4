//! The preset parser on arbitrary text: never a panic; whatever parses saves and parses back
//! to the same weather (the file format round-trips), and its errors always carry a message.
#![no_main]

use nimbus::Weather;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Weather::from_toml(text, "<fuzz>") {
        Ok(w) => {
            let again = Weather::from_toml(&w.to_toml(), "<round trip>")
                .expect("a parsed preset saves to a loadable file");
            assert_eq!(again, w, "the preset file format round-trips");
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
});
