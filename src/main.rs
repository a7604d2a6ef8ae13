fn main() {
    let p = hapticlab::profile::LoadedProfile::thesis();
    println!("{}", p.profile.name);
}
