module mavconform/tools/vectors_go

go 1.25.0

require github.com/bluenviron/gomavlib/v3 v3.3.5
