"""Quality-assurance tools of the repository, run by hand from its root or by the tests (not
installed with the package):

* :mod:`.fault_audit` — ``python3 -m qa.fault_audit --out DIR``: bad inputs through the
  command line, each classified by what the user sees; its cases in :mod:`.fault_cases`,
  the files they plant built by :mod:`.planted_files`;
* :mod:`.kill_audit` — ``python3 -m qa.kill_audit --kills 20 --out DIR``: runs killed at
  random moments leave readable result files and resume bit for bit;
* :mod:`.assertion_counts` — the assertions per test module;
* :mod:`.fixtures` — the fixture files of ``tests/fixtures/`` (scenes, meshes), read by the
  tests and the fault audit alike.
"""
