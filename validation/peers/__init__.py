"""Adapters to peer codes used as references; each is optional. Also our own full-FE
reference of the point mass on the beam (:mod:`validation.peers.full_fe_contact`), which
needs nothing beyond ffrmbs's dependencies."""
