"""Seeing a model: the meshcat live view and offline HTML (viewer.py, scene.py), plots and
screenshots."""
