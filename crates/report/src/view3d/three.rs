//! three.js's module build as a classic script's constant `THREE`, so that it can be inlined
//! in the page with the scene's script after it (an inline module cannot import another).

/// `module` (one file, no imports, one `export{local as Name, ...};` at its end) with its export
/// clause turned into `const THREE = (() => { ...; return {Name: local, ...}; })();`.
pub fn as_classic(module: &str) -> Result<String, String> {
    let start = module
        .rfind("export{")
        .ok_or("three.js's module has no export clause")?;
    let rest = &module[start + "export{".len()..];
    let end = rest
        .find('}')
        .ok_or("three.js's export clause is not closed")?;
    if !rest[end + 1..]
        .trim()
        .trim_start_matches(';')
        .trim()
        .is_empty()
    {
        return Err("three.js's module goes on after its export clause".into());
    }
    let imports = ["import{", "import*", "import\"", "import "]
        .iter()
        .any(|i| module.contains(i));
    if imports || module.to_ascii_lowercase().contains("</script") {
        return Err("three.js's module cannot be inlined (it closes a script or imports)".into());
    }
    let entries: Vec<String> = rest[..end]
        .split(',')
        .map(|entry| match entry.trim().split_once(" as ") {
            Some((local, name)) => format!("{name}:{local}"),
            None => entry.trim().to_string(),
        })
        .collect();
    Ok(format!(
        "const THREE=(()=>{{{}\nreturn{{{}}};}})();",
        &module[..start],
        entries.join(",")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_export_clause_becomes_the_returned_object() {
        let got = as_classic("const a=1,b=2;function c(){}export{a as A,b as B,c};").unwrap();
        assert_eq!(
            got,
            "const THREE=(()=>{const a=1,b=2;function c(){}\nreturn{A:a,B:b,c};})();"
        );
    }

    #[test]
    fn a_module_with_more_after_its_exports_is_refused() {
        assert!(as_classic("const a=1;export{a as A};a();").is_err());
    }

    /// The vendored file is the one assets/three/README.md names.
    #[test]
    fn the_vendored_three_js_is_the_pinned_release() {
        use sha2::Digest;
        let digest = sha2::Sha256::digest(super::super::THREE_MODULE.as_bytes());
        let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(hex, super::super::THREE_SHA256);
        let readme = include_str!("../../assets/three/README.md");
        assert!(
            readme.contains(super::super::THREE_SHA256)
                && readme.contains(super::super::THREE_RELEASE)
        );
        assert!(as_classic(super::super::THREE_MODULE)
            .unwrap()
            .contains("WebGLRenderer:"));
    }
}
