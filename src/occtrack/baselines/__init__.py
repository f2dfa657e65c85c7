"""Baselines that users can pick instead of occtrack's trackers, scored in the same tables."""
