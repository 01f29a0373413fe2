"""The web viewer: a run as one self-contained HTML page (three.js + the run's glTF inside)."""

from zoetic.web.page import bundle_path, page_html, write_html

__all__ = ["bundle_path", "page_html", "write_html"]
