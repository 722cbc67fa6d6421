"""Time-domain references: Newmark integration to the periodic state (:mod:`..timeint`) and
run-ups through a band (:mod:`..runup`)."""
