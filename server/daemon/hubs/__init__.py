"""Hubs in the daemon: the backend interface every kind of hub implements (backend.py), one actor per
hub that owns its link and serves operations one at a time (actor.py), and the registry that finds,
starts and stops them (manager.py)."""
