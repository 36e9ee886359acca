"""gausspp.simulation."""
