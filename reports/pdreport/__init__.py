"""libpd verification report: stages (run the C++ tools), render (HTML + PNG), compare (CI diff)."""
