"""realm-ms asset pipeline: sources -> repaired, scaled, decomposed, annotated catalog objects."""
