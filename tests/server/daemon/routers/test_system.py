"""What the daemon says about itself."""

from openbricks import __version__
from openbricks_server.daemon.store.migrations import MIGRATIONS


def test_version_health_and_data_dir(daemon, viewer):
    assert viewer.get("/api/system/version").json() == {
        "version": __version__,
        "schema_version": len(MIGRATIONS),
    }
    health = viewer.get("/api/system/health").json()
    assert health["ok"] and health["boot"] == daemon.ctx.events.boot_id
    where = viewer.get("/api/system/data-dir").json()
    assert where["database"].endswith("console.sqlite3") and where["database_bytes"] > 0


def test_the_docs_page_is_served_without_a_cdn(daemon, operator):
    page = operator.get("/docs")
    assert page.status_code == 200 and "/static/docs/swagger-ui-bundle.js" in page.text
    assert "cdn" not in page.text.lower()
    assert operator.get("/static/docs/swagger-ui-bundle.js").status_code == 200
