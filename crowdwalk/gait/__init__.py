"""Gait generation from sagittal elevation angles (Sun & Metaxas 2001): ElevInterp,
ElevWalker, MetaGait and the batched Animator the crowd drives."""
