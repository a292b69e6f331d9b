"""One part from file to result: `file.inspect_file` reads, checks health, repairs what was
asked and integrates; `align` puts a part into its principal frame. The CLI's `inspect` and
`align`, the batches, robot models and scenes all come here for a mesh's mass properties."""
