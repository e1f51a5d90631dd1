"""Helpers shared by the tests (state writers, checkers); not tests themselves."""
