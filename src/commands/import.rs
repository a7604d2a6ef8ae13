//! `hapticlab import`: runs the conversion ([`crate::import`], where the
//! flags are defined with it) and lists the recordings written.

use crate::import::ImportArgs;
use crate::support::Failure;

pub fn run(args: ImportArgs) -> Result<(), Failure> {
    let written = crate::import::run(&args)?;
    for p in &written {
        crate::outln!("{}", p.display());
    }
    crate::errln!("imported {} recording(s)", written.len());
    Ok(())
}
