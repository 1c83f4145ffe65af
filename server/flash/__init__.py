"""`openbricks flash`: image inspection, signature check, release download, esptool, naming the hub."""
