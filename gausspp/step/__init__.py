"""gausspp.step."""
