"""Suite-wide pytest configuration."""


def pytest_collection_modifyitems(config, items):
    """Run the fast unit tests first and the slow end-to-end ones last, in one session."""
    items.sort(key=lambda item: item.get_closest_marker("e2e") is not None)
