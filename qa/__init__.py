"""Quality-assurance tools run by hand or by the tests: the fault audit, the kill audit and
the assertion count of the test suite."""
