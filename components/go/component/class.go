package component

import (
	"fmt"
	"regexp"

	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

// Class is a kind of component a process can make instances of.
type Class struct {
	name, version, summary string
	interfaces             []string
	create                 func(*Properties) (any, error)
	declaresParameters     bool
	parameters             []Parameter
	capabilities           []string
}

// NewClass describes a class: its name (unique on a host,
// lower_snake_case), its semantic version "MAJOR.MINOR.PATCH", a one-line
// summary, and the constructor of its instances. The interfaces served
// are those T implements, so T must be a concrete type (e.g. *MyBSDF),
// not an interface. If an instance implements io.Closer, Close is called
// when it is released.
func NewClass[T any](name, version, summary string, create func(*Properties) (T, error)) Class {
	var zero T
	class := Class{name: name, version: version, summary: summary, interfaces: interfaceNames(zero)}
	if create != nil {
		class.create = func(p *Properties) (any, error) { return create(p) }
	}
	return class
}

// Name is the class name.
func (c Class) Name() string { return c.name }

// Interfaces lists the full names of the services the class implements.
func (c Class) Interfaces() []string { return append([]string(nil), c.interfaces...) }

var (
	classNamePattern = regexp.MustCompile(`^[a-z][a-z0-9_]*$`)
	versionPattern   = regexp.MustCompile(`^[0-9]+\.[0-9]+\.[0-9]+$`)
)

// check reports what makes the class unservable.
func (c Class) check() error {
	switch {
	case !classNamePattern.MatchString(c.name):
		return fmt.Errorf("class name %q is not lower_snake_case", c.name)
	case !versionPattern.MatchString(c.version):
		return fmt.Errorf("class %s: version %q is not MAJOR.MINOR.PATCH", c.name, c.version)
	case len(c.interfaces) == 0:
		return fmt.Errorf("class %s implements no interface this package serves", c.name)
	case c.create == nil:
		return fmt.Errorf("class %s has no constructor", c.name)
	}
	if err := c.checkCapabilities(); err != nil {
		return err
	}
	return c.checkParameters()
}

// info is what Describe answers for the class and its instances.
func (c Class) info(origin string) *yarfv1.ComponentInfo {
	return &yarfv1.ComponentInfo{
		ClassName:  c.name,
		Version:    c.version,
		Interfaces: c.Interfaces(),
		Summary:    c.summary,
		Origin:     origin,

		DeclaresParameters: c.declaresParameters,
		Parameters:         c.parameterInfos(),
		Capabilities:       c.capabilities,
	}
}
