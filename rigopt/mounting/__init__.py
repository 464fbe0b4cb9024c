"""Where cameras may go on a vehicle: the mount rules, mount points on the zones and their clear directions."""
