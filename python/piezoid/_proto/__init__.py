"""Generated from proto/ by setup.py when the package is built: the *_pb2.py modules are not in git."""
