//! The list against the code: every field declared, every choice the parser's,
//! one option labelling any analysis.

use super::*;

#[test]
fn every_analysis_field_is_declared_once() {
    let names = field_names(&Analysis::default());
    for n in &names {
        assert_eq!(
            ANALYSIS_OPTIONS.iter().filter(|o| o.field() == *n).count(),
            1,
            "analysis.{n} must be declared once in ANALYSIS_OPTIONS"
        );
    }
    assert_eq!(
        names.len(),
        ANALYSIS_OPTIONS.len(),
        "an option that is no field"
    );
    // What serde writes of an analysis is among the options, too.
    let v = serde_json::to_value(Analysis::default()).unwrap();
    for key in v.as_object().unwrap().keys() {
        assert!(
            option(key).is_some(),
            "analysis.{key} is not in ANALYSIS_OPTIONS"
        );
    }
}

#[test]
fn a_difference_in_sub_windows_is_a_difference() {
    let a = Analysis::default();
    let mut b = a.clone();
    assert!(first_difference(&a, &b).is_none());
    b.windows = Some(crate::profile::Windows {
        length: 0.01,
        hop: 0.005,
    });
    // Sub-windows change the DFT length too, so welch_segment's
    // comparison may name it first; windows itself differs either way.
    assert!(first_difference(&a, &b).is_some());
    let w = option("windows").unwrap();
    assert!(!(w.same)(&a, &b));
    assert!((w.value)(&b).contains("0.005"));
}

#[test]
fn bins_do_not_matter_under_a_band() {
    let a = Analysis {
        band: Some([1.0, 2.0]),
        ..Analysis::default()
    };
    let mut b = a.clone();
    b.bins = [1, 3];
    assert!(first_difference(&a, &b).is_none());
}

/// `analysis`'s text set to `toml`: the field set by a profile's words.
fn analysis_with(field: &str, value: &str) -> Result<Analysis, String> {
    let mut t = toml::Table::try_from(Analysis::default()).unwrap();
    let v: toml::Table = toml::from_str(&format!("v = {value}"))
        .or_else(|_| toml::from_str(&format!("v = {value:?}")))
        .map_err(|e| e.to_string())?;
    t.insert(field.into(), v["v"].clone());
    toml::Value::Table(t)
        .try_into()
        .map_err(|e: toml::de::Error| e.to_string())
}

#[test]
fn every_searched_value_is_one_the_option_takes() {
    for o in ANALYSIS_OPTIONS.iter().filter(|o| !o.search.is_empty()) {
        assert!(o.sweepable, "{}", o.name);
        for v in o.search {
            let relative = v.starts_with("points/") || v.starts_with("window/");
            let left_out = *v == "none" && o.kind != Kind::Choice;
            if !(relative || left_out) {
                analysis_with(o.field(), v).unwrap_or_else(|e| panic!("{}: {v}: {e}", o.name));
            }
        }
    }
}

/// An analysis-only profile with `line` added to `table`.
fn profile_with(table: &str, line: &str) -> Result<crate::profile::LoadedProfile, String> {
    let mut analysis = "channel = \"acc\"\naxis = \"t_s\"\nwindow = [0.0, 0.999]\n\
                        spacing = 0.001\nbins = [1, 8]\n"
        .to_string();
    let mut classifier = "k = 1\n".to_string();
    let t = if table == "analysis" {
        &mut analysis
    } else {
        &mut classifier
    };
    // A key is written once: the default line goes.
    let key = line.split(" = ").next().unwrap();
    *t = t
        .lines()
        .filter(|l| !l.starts_with(&format!("{key} = ")))
        .map(|l| format!("{l}\n"))
        .collect::<String>()
        + line
        + "\n";
    let text = format!(
        "name = \"t\"\n[analysis]\n{analysis}[classifier]\n{classifier}[evaluation]\n\
         method = \"holdout\"\ntrain_per_class = 5\ntest_per_class = 5\n"
    );
    crate::profile::LoadedProfile::from_str(&text, "t.toml", std::path::Path::new("."))
        .map_err(|e| e.to_string())
}

/// Every word of every choice is one the profile's parser takes, and a
/// word outside them is refused at its key with the declared words.
#[test]
fn every_choice_lists_the_words_the_parser_accepts() {
    let choices = ANALYSIS_OPTIONS
        .iter()
        .map(|o| (o.name, o.kind, o.allowed))
        .chain(
            CLASSIFIER_OPTIONS
                .iter()
                .map(|o| (o.name, o.kind, o.allowed)),
        )
        .filter(|(_, k, _)| *k == Kind::Choice);
    let mut checked = 0;
    for (name, _, allowed) in choices {
        let (table, field) = name.split_once('.').unwrap();
        for w in allowed {
            profile_with(table, &format!("{field} = {w:?}"))
                .unwrap_or_else(|e| panic!("{name} = {w:?} is listed but refused: {e}"));
        }
        let e = profile_with(table, &format!("{field} = \"wobbly\"")).unwrap_err();
        assert!(
            e.contains(&format!(
                "{name}: must be {}, got \"wobbly\"",
                words(allowed)
            )),
            "{e}"
        );
        // The parser's own list (serde's, for an enum) is the same.
        let parsed = match table {
            "analysis" => analysis_with(field, "wobbly").err(),
            _ => {
                let text = format!("k = 1\n{field} = \"wobbly\"");
                toml::from_str::<Classifier>(&text)
                    .err()
                    .map(|e| e.to_string())
            }
        };
        if let Some(e) = parsed.filter(|e| e.contains("expected one of")) {
            let listed: Vec<&str> = e
                .split("expected one of ")
                .nth(1)
                .and_then(|l| l.lines().next())
                .unwrap()
                .split(", ")
                .map(|w| w.trim().trim_matches('`'))
                .collect();
            assert_eq!(listed, allowed.to_vec(), "{name}: {e}");
        }
        checked += 1;
    }
    assert!(checked >= 6, "{checked} choices");
    let e = profile_with("classifier", "standardize = \"yes\"").unwrap_err();
    assert!(
        e.contains("classifier.standardize: must be true or false"),
        "{e}"
    );
}

/// One option labels the features of any analysis.
#[test]
fn exactly_one_option_labels_the_features() {
    let bands = crate::profile::Bands {
        count: 8,
        from: 1.0,
        to: 100.0,
        scale: crate::profile::BandScale::Log,
    };
    for (band, bands, cepstra, want) in [
        (None, None, None, "bins"),
        (Some([1.0, 2.0]), None, None, "band"),
        (None, Some(bands), None, "bands"),
        (None, Some(bands), Some(4), "cepstra"),
        (None, None, Some(4), "bins"),
    ] {
        let a = Analysis {
            band,
            bands,
            cepstra,
            ..Analysis::default()
        };
        let labelling: Vec<&str> = ANALYSIS_OPTIONS
            .iter()
            .filter(|o| o.labels.is_some_and(|l| l(&a).is_some()))
            .map(|o| o.field())
            .collect();
        assert_eq!(labelling, [want]);
    }
    let a = Analysis {
        bands: Some(bands),
        cepstra: Some(4),
        drop_level: true,
        ..Analysis::default()
    };
    assert_eq!(FeatureNames::of(&a), FeatureNames::Cepstra { first: 1 });
}

/// Each option's line as a profile writes it reads back as its value:
/// the lines of an analysis (and a classifier) make the same one again.
#[test]
fn written_lines_read_back_as_the_values() {
    let a = Analysis {
        channel: "vib".into(),
        axis: "t_s".into(),
        window: [0.0, 5.99],
        spacing: 1.0 / 2200.0,
        spectrum: SpectrumKind::LogWelch,
        taper: crate::profile::Taper::Hann,
        welch_segment: Some(256),
        welch_overlap: Some(0.25),
        bands: Some(crate::profile::Bands {
            count: 32,
            from: 68.7,
            to: 1100.0,
            scale: crate::profile::BandScale::Log,
        }),
        cepstra: Some(13),
        drop_level: true,
        windows: Some(crate::profile::Windows {
            length: 1.49,
            hop: 0.745,
        }),
        channels: vec!["acc".into()],
        ..Analysis::default()
    };
    let text: String = ANALYSIS_OPTIONS
        .iter()
        .filter_map(|o| Some(format!("{} = {}\n", o.field(), o.written(&a)?)))
        .collect();
    assert!(!text.contains("bins"), "bands replace bins:\n{text}");
    assert!(
        text.contains("bands = { count = 32, from = 68.7, to = 1100.0, scale = \"log\" }"),
        "{text}"
    );
    let back: Analysis = toml::from_str(&text).unwrap();
    assert_eq!(
        back,
        Analysis {
            bins: back.bins,
            ..a
        }
    );
    let c = Classifier {
        k: 3,
        metric: super::super::Metric::Cosine,
        standardize: true,
        k_candidates: Some(vec![1, 3]),
        ..Classifier::default()
    };
    let text: String = CLASSIFIER_OPTIONS
        .iter()
        .filter_map(|o| Some(format!("{} = {}\n", o.field(), o.written(&c)?)))
        .collect();
    assert_eq!(toml::from_str::<Classifier>(&text).unwrap(), c);
    let auto = Classifier {
        k: super::super::K_AUTO,
        ..c
    };
    assert_eq!(
        classifier_option("k").unwrap().written(&auto).unwrap(),
        "\"auto\""
    );
}
