// Package component hosts yarf component classes in a Go process and serves
// them over gRPC, so that yarfd (or any client) can make and use instances
// of them as it does with its own C++ plugins.
//
// A class is a constructor from Properties to a value implementing one or
// more interfaces of this package (SurfaceModel, Sampler); NewClass finds
// which from the value's type. Serve (or Main, for a command) listens,
// answers yarf.v1.Component, Factory and Registry for the classes given,
// routes each interface's calls to the instance named by their handle, and
// optionally keeps the process registered with a yarfd.
//
//	func main() {
//		component.Main(component.NewClass("my_bsdf", "1.0.0",
//			"What it is, in one line", NewMyBSDF))
//	}
package component
