"""Occlusion models: one interface, chosen by name; the filter never asks which one it holds."""
