"""gausspp.model."""
