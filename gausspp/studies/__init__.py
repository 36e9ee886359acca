"""gausspp.studies."""
