//! Random kernels, interval quantiles, the ridge and the LDA through the one
//! model: what is fitted comes from the training examples alone, the model
//! file carries it (format v2), and a spectrum + k-NN model is still v1.

use std::path::Path;

use hapticlab::analysis::kernels::KernelTransform;
use hapticlab::classify::{ClassifyError, MODEL_FORMAT, MODEL_FORMAT_V2, Model, TrainingExample};
use hapticlab::profile::{Analysis, Classifier, FeatureFamily, Method};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// 64 points along t_s, 1 ms apart.
fn analysis(features: FeatureFamily) -> Analysis {
    Analysis {
        channel: "f".into(),
        axis: "t_s".into(),
        window: [0.0, 0.063],
        spacing: 0.001,
        features,
        kernel_features: (features == FeatureFamily::Kernels).then_some(840),
        ..Analysis::default()
    }
}

fn ridge() -> Classifier {
    Classifier {
        method: Method::Ridge,
        ..Classifier::default()
    }
}

fn lda() -> Classifier {
    Classifier {
        method: Method::Lda,
        ..Classifier::default()
    }
}

/// Three textures of 64 points: a fast sine, a slow sine, a square wave,
/// each with a random phase and noise. For random kernels the examples
/// are the window's points, as the analysis hands them on.
fn windows(per_class: usize, seed: u64) -> Vec<(String, Vec<f64>)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    for i in 0..per_class {
        for (label, period, square) in [
            ("fast", 6.0, false),
            ("slow", 17.0, false),
            ("square", 11.0, true),
        ] {
            let phase: f64 = rng.random_range(0.0..std::f64::consts::TAU);
            let w: Vec<f64> = (0..64)
                .map(|t| {
                    let s = (t as f64 * std::f64::consts::TAU / period + phase).sin();
                    let v = if square { s.signum() } else { s };
                    v + 0.4 * rng.random_range(-1.0..1.0)
                })
                .collect();
            out.push((format!("{label}/{seed}_{i}"), w));
        }
    }
    out
}

fn examples(set: &[(String, Vec<f64>)]) -> Vec<TrainingExample> {
    set.iter()
        .map(|(file, w)| TrainingExample {
            file: file.clone(),
            label: file.split('/').next().unwrap().to_string(),
            features: w.clone(),
        })
        .collect()
}

/// Quantile features of each window, as the analysis makes them.
fn quantile_examples(set: &[(String, Vec<f64>)]) -> Vec<TrainingExample> {
    let mut q = hapticlab::analysis::quantiles::Quantiles::new(64);
    examples(set)
        .into_iter()
        .map(|mut e| {
            let mut out = vec![0.0; q.len()];
            q.compute(&e.features, &mut out);
            e.features = out;
            e
        })
        .collect()
}

fn accuracy(model: &Model, test: &[TrainingExample]) -> usize {
    test.iter()
        .filter(|e| model.classify(&e.features).unwrap().label == e.label)
        .count()
}

#[test]
fn the_kernels_biases_come_from_the_training_windows_alone() {
    let a = analysis(FeatureFamily::Kernels);
    let train = examples(&windows(10, 1));
    let test = examples(&windows(10, 2));
    let model = Model::train("t", &a, &ridge(), train.clone()).unwrap();
    let windows: Vec<&[f64]> = train.iter().map(|e| e.features.as_slice()).collect();
    let fitted = KernelTransform::fit(&windows, 64, 1, 840).unwrap();
    assert!(model.kernels.as_ref() == Some(&fitted));
    assert_eq!(model.fitted_feature_count(), 840);
    // Had the test windows been among them, the biases would differ.
    let mut all = train.clone();
    all.extend(test.iter().cloned());
    let leaky = Model::train("t", &a, &ridge(), all).unwrap();
    assert!(leaky.kernels != model.kernels);
    // Classifying changes nothing fitted.
    let before = model.clone();
    let right = accuracy(&model, &test);
    assert!(model == before);
    assert!(right >= 27, "{right} of 30");
    let p = model.classify(&test[0].features).unwrap();
    assert_eq!(p.votes.iter().map(|(_, v)| v).sum::<usize>(), 1);
    assert!(p.neighbours.is_empty());
}

#[test]
fn kernels_with_knn_and_quantiles_with_either_classifier_tell_the_textures_apart() {
    let knn = Classifier {
        k: 3,
        ..Classifier::default()
    };
    let k = analysis(FeatureFamily::Kernels);
    let model = Model::train("t", &k, &knn, examples(&windows(10, 3))).unwrap();
    assert!(model.ridge.is_none() && model.kernels.is_some());
    assert!(accuracy(&model, &examples(&windows(10, 4))) >= 27);
    let q = analysis(FeatureFamily::Quantiles);
    assert_eq!(
        q.feature_count(),
        quantile_examples(&windows(1, 0))[0].features.len()
    );
    for c in [ridge(), knn] {
        let model = Model::train("t", &q, &c, quantile_examples(&windows(10, 5))).unwrap();
        assert!(model.kernels.is_none());
        let right = accuracy(&model, &quantile_examples(&windows(10, 6)));
        assert!(right >= 27, "{:?}: {right} of 30", c.method);
    }
}

/// A model of random kernels and `classifier`, trained, written as v2
/// and read back equal, with the same answers; and its text.
fn kernel_model_loads_back(classifier: &Classifier) -> (Model, String) {
    let a = analysis(FeatureFamily::Kernels);
    let model = Model::train("t", &a, classifier, examples(&windows(5, 7))).unwrap();
    assert_eq!(model.format, MODEL_FORMAT_V2);
    let text = serde_json::to_string_pretty(&model).unwrap();
    let back = Model::from_json(&text, Path::new("m.json")).unwrap();
    assert!(back == model);
    for e in examples(&windows(3, 8)) {
        assert_eq!(
            back.classify(&e.features).unwrap(),
            model.classify(&e.features).unwrap()
        );
    }
    (model, text)
}

#[test]
fn a_fitted_model_is_format_v2_and_loads_back_with_its_answers() {
    let (_, text) = kernel_model_loads_back(&ridge());
    let path = Path::new("m.json");
    // A v1 tag on it, or a part missing, is a clear refusal.
    let v1 = text.replace(MODEL_FORMAT_V2, MODEL_FORMAT);
    let err = Model::from_json(&v1, path).unwrap_err().to_string();
    assert!(err.contains("holds no kernels, ridge or LDA"), "{err}");
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    value.as_object_mut().unwrap().remove("ridge");
    let err = Model::from_json(&value.to_string(), path)
        .unwrap_err()
        .to_string();
    assert!(err.contains("has no ridge"), "{err}");
    let mut value: serde_json::Value = serde_json::from_str(&text).unwrap();
    value["kernels"]["biases"][0][5] = serde_json::json!(null);
    assert!(Model::from_json(&value.to_string(), path).is_err());
}

#[test]
fn a_spectrum_knn_model_is_still_written_as_v1() {
    let a = hapticlab::profile::LoadedProfile::thesis().profile;
    let train: Vec<TrainingExample> = (0..12)
        .map(|i| TrainingExample {
            file: format!("{i}.csv"),
            label: ["S1", "S2"][i % 2].into(),
            features: (0..49).map(|j| ((i * j) % 7) as f64).collect(),
        })
        .collect();
    let m = Model::train("thesis", &a.analysis, &a.classifier, train).unwrap();
    assert_eq!(m.format, MODEL_FORMAT);
    let value = serde_json::to_value(&m).unwrap();
    for key in ["kernels", "ridge", "lda"] {
        assert!(value.get(key).is_none(), "{key}");
    }
    assert!(value["analysis"].get("features").is_none());
    assert!(value["analysis"].get("kernel_features").is_none());
    assert!(value["classifier"].get("method").is_none());
}

#[test]
fn lda_tells_the_textures_apart_on_kernels_quantiles_and_spectrum_features() {
    // Kernels: 840 features against 30 windows (Woodbury's way); the
    // kernels still fitted on the training windows alone.
    let a = analysis(FeatureFamily::Kernels);
    let train = examples(&windows(10, 1));
    let model = Model::train("t", &a, &lda(), train.clone()).unwrap();
    let w: Vec<&[f64]> = train.iter().map(|e| e.features.as_slice()).collect();
    assert!(model.kernels.as_ref() == Some(&KernelTransform::fit(&w, 64, 1, 840).unwrap()));
    assert!(model.ridge.is_none() && model.scaling.is_none());
    let fit = model.lda.as_ref().unwrap();
    assert_eq!((fit.weights.len(), fit.weights[0].len()), (3, 840));
    assert!(
        fit.shrinkage.iter().all(|s| *s > 0.0 && *s <= 1.0),
        "{:?}",
        fit.shrinkage
    );
    let test = examples(&windows(10, 2));
    let before = model.clone();
    let right = accuracy(&model, &test);
    assert!(model == before);
    assert!(right >= 27, "kernels: {right} of 30");
    let p = model.classify(&test[0].features).unwrap();
    assert_eq!(p.votes.iter().map(|(_, v)| v).sum::<usize>(), 1);
    assert_eq!(p.votes[0], (p.label.clone(), 1));
    assert!(p.neighbours.is_empty());
    // A recording's sub-windows vote as the ridge's do: one each.
    let windows_of: Vec<Vec<f64>> = test[..6].iter().map(|e| e.features.clone()).collect();
    let voted = model.classify_windows(&windows_of).unwrap();
    assert_eq!(voted.tally.iter().map(|t| t.windows).sum::<usize>(), 6);
    // Quantiles: more features than the 60 windows as well.
    let q = analysis(FeatureFamily::Quantiles);
    let model = Model::train("t", &q, &lda(), quantile_examples(&windows(20, 5))).unwrap();
    assert!(model.kernels.is_none() && model.lda.is_some());
    assert!(q.feature_count() > 60);
    let right = accuracy(&model, &quantile_examples(&windows(10, 6)));
    assert!(right >= 27, "quantiles: {right} of 30");
    // The thesis's spectrum settings: 49 features against 24 examples
    // (two well-separated classes of 12); then 96 examples (the direct
    // solve).
    let thesis = hapticlab::profile::LoadedProfile::thesis().profile;
    let spectra = |seed: u64, n: usize| -> Vec<TrainingExample> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|i| TrainingExample {
                file: format!("{seed}_{i}.csv"),
                label: ["S1", "S2"][i % 2].into(),
                features: (0..49)
                    .map(|j| {
                        let peak = if i % 2 == 0 { 10 } else { 30 };
                        -8.0 + 3.0 * (-((j as f64 - peak as f64) / 4.0).powi(2)).exp()
                            + 0.5 * rng.random_range(-1.0..1.0)
                    })
                    .collect(),
            })
            .collect()
    };
    for n in [24, 96] {
        let model = Model::train("t", &thesis.analysis, &lda(), spectra(1, n)).unwrap();
        assert_eq!(model.format, MODEL_FORMAT_V2);
        assert_eq!(accuracy(&model, &spectra(2, 24)), 24, "{n} examples");
    }
}

#[test]
fn an_lda_model_loads_back_with_its_answers_and_is_checked_as_the_ridge_is() {
    let a = analysis(FeatureFamily::Kernels);
    let (model, text) = kernel_model_loads_back(&lda());
    let path = Path::new("m.json");
    let refused = |value: serde_json::Value, says: &str| {
        let err = Model::from_json(&value.to_string(), path)
            .unwrap_err()
            .to_string();
        assert!(err.contains(says), "{says:?} missing: {err}");
    };
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut v1 = value.clone();
    v1["format"] = serde_json::json!(MODEL_FORMAT);
    refused(v1, "holds no kernels, ridge or LDA");
    let mut gone = value.clone();
    gone.as_object_mut().unwrap().remove("lda");
    refused(gone, "has no LDA");
    let mut knn = value.clone();
    knn["classifier"].as_object_mut().unwrap().remove("method");
    refused(knn, "it has an LDA but classifier.method is not \"lda\"");
    let mut short = value.clone();
    short["lda"]["centre"].as_array_mut().unwrap().pop();
    refused(short, "its LDA must have 3 rows of 840 finite weights");
    let mut shrunk = value.clone();
    shrunk["lda"]["shrinkage"][0] = serde_json::json!(1.5);
    refused(shrunk, "shrinkage intensities from 0 to 1");
    // A profile's other method is refused by key; its k, metric and
    // weights are not the LDA's business.
    let err = model.check_classifier(&ridge()).unwrap_err();
    assert!(
        matches!(
            &err,
            ClassifyError::SettingsDiffer {
                field: "classifier.method",
                ..
            }
        ),
        "{err}"
    );
    let other = Classifier {
        k: 3,
        standardize: true,
        ..lda()
    };
    assert!(model.check_classifier(&other).is_ok());
    // No k to adapt: five scans a texture under k = 10 train as asked.
    let adapted = Model::train_adapting_k("t", &a, &lda(), examples(&windows(5, 7))).unwrap();
    assert!(adapted.k_fallback.is_none() && adapted.k_selection.is_none());
    assert!(adapted == model);
    assert!(adapted.k_notice().is_none());
    // One training window a texture: no covariance, refused in words.
    let err = Model::train("t", &a, &lda(), examples(&windows(1, 9)))
        .unwrap_err()
        .to_string();
    assert!(err.contains("no covariance to estimate"), "{err}");
}
