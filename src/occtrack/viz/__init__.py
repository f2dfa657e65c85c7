"""Pictures of what the tracker believed: frames, scenes, runs. matplotlib, Agg backend."""
