"""Renderers: message objects (from the wire or a bag) to YAML, JSON, CSV and tables."""
