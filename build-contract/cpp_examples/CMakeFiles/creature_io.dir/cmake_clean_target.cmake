file(REMOVE_RECURSE
  "libcreature_io.a"
)
