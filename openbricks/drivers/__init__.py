"""One module per supported component; import the one your wiring uses (nothing is imported eagerly)."""
