# Test suites of src/io.
