"""openbricks_server: the host side: hub links, the openbricks CLI and the console daemon."""
