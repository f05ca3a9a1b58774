"""Adapters to peer codes used as references; each is optional."""
