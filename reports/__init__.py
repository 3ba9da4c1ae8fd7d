"""rtlab's pages: lesson pages and the course site (reports.lesson, reports.site), a graded
submission's feedback page (``reports.feedback_page(result, out)``) and the class page."""

from reports.feedback import feedback_page

__all__ = ["feedback_page"]
