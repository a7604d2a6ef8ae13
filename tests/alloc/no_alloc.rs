//! After its first call, feature extraction allocates nothing: the FFT plan,
//! its scratch and every buffer are made once and reused.

use hapticlab::analysis::FeatureExtractor;
use hapticlab::profile::LoadedProfile;

use crate::counting_alloc::allocations;

#[test]
fn features_do_not_allocate_after_the_first_call() {
    let analysis = LoadedProfile::thesis().profile.analysis;
    let x: Vec<f64> = (0..9000).map(|j| j as f64 * 1e-5).collect();
    let y: Vec<f64> = x.iter().map(|x| (x * 1500.0).sin()).collect();
    let mut fx = FeatureExtractor::new(&analysis);
    fx.features(&x, &y).unwrap();
    let before = allocations();
    for _ in 0..10 {
        assert_eq!(fx.features(&x, &y).unwrap().len(), 49);
        assert_eq!(fx.resample(&x, &y).unwrap().len(), 100);
    }
    assert_eq!(allocations() - before, 0);
    // The counter does count.
    let v = std::hint::black_box(vec![0u8; 16]);
    assert_eq!(allocations() - before, 1);
    drop(v);
}
