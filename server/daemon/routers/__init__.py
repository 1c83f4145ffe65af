"""One FastAPI router per resource, each included under `/api` by `create_app`."""
