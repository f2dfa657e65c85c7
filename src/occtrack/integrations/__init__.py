"""occtrack inside other libraries' pipelines. Each module needs its own optional extra:
`occtrack.integrations.supervision` needs `pip install "occtrack[supervision]"`."""
