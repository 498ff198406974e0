// The plugin of adapter foo.
