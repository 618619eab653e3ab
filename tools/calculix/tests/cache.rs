//! The report's result cache (`ccx::set_cache`): a deck solved once is read back, not solved
//! again; another deck is solved. (Its own test binary: the cache is process-wide.)
use finger_calculix::beam_compliance;
use finger_calculix::ccx::{set_cache, Kind};
use finger_calculix::mesh::Density;
use finger_model::Params;

#[test]
fn a_deck_solved_once_is_read_back() {
    let dir = std::env::temp_dir().join(format!("finger-calculix-cache-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    set_cache(Some(dir.clone()));
    let p = Params::<f64>::default();
    let d = Density::coarse();
    let dats = || -> Vec<std::path::PathBuf> {
        let mut v: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).filter(|f| f.extension().is_some_and(|x| x == "dat")).collect();
        v.sort();
        v
    };
    let a = beam_compliance(&p, 20.0, Kind::PlaneStrain, &d).unwrap();
    assert_eq!(dats().len(), 1);
    // its CPU time beside it
    let f = dats().remove(0);
    let cpu: f64 = std::fs::read_to_string(f.with_extension("cpu")).unwrap().trim().parse().unwrap();
    assert!((0.0..60.0).contains(&cpu), "{cpu} s");
    // the kept .dat is what the second run reads: change it and the answer follows
    let dat = std::fs::read_to_string(&f).unwrap();
    let b = beam_compliance(&p, 20.0, Kind::PlaneStrain, &d).unwrap();
    assert_eq!(a, b);
    std::fs::write(&f, dat.replace("E-0", "E-9")).unwrap();
    let c = beam_compliance(&p, 20.0, Kind::PlaneStrain, &d).unwrap();
    assert_ne!(a, c, "the second run solved the deck again");
    let _ = beam_compliance(&p, 25.0, Kind::PlaneStrain, &d).unwrap();
    assert_eq!(dats().len(), 2, "another deck is solved and kept");
    set_cache(None);
    let _ = std::fs::remove_dir_all(&dir);
}
