"""`openbricks flash`: image inspection, signature check, releases (cached or from a set location),
esptool, naming the hub."""
