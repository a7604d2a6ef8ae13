//! The USB transport (nusb): not written yet.
