package component

import (
	"fmt"

	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

// Parameter is one property a class accepts, as Describe tells it
// (yarf.v1.ParameterInfo): yarfd refuses at Submit a scene giving a class
// that declares its parameters any other property, or a value of another
// kind, out of range or not among the choices.
type Parameter struct {
	Name string
	// Type is one of ParameterInfo's: "bool", "int", "float", "string",
	// "rgb", "vector", "transform", "float array", "float or texture",
	// "rgb or texture", "material", "rgb or grid", "file".
	Type string
	// Default is the value used when the key is absent, as text ("0.5",
	// "ggx", "1, 1, 1"); "" for none. The getter's own default must be it.
	Default  string
	Required bool
	// Min and Max bound a number, or every channel of a colour; nil: none.
	Min, Max *float64
	Choices  []string
	Doc      string
}

var parameterTypes = map[string]bool{
	"bool": true, "int": true, "float": true, "string": true, "rgb": true, "vector": true,
	"transform": true, "float array": true, "float or texture": true, "rgb or texture": true,
	"material": true, "rgb or grid": true, "file": true,
}

// Bound is a pointer to v, for Parameter.Min and Parameter.Max.
func Bound(v float64) *float64 { return &v }

// WithParameters is the class declaring its parameters (all of them).
func (c Class) WithParameters(parameters ...Parameter) Class {
	c.parameters = append([]Parameter(nil), parameters...)
	c.declaresParameters = true
	return c
}

// checkParameters reports what makes a declaration unreadable to yarfd.
func (c Class) checkParameters() error {
	seen := map[string]bool{}
	for _, p := range c.parameters {
		switch {
		case p.Name == "":
			return fmt.Errorf("class %s declares a parameter without a name", c.name)
		case seen[p.Name]:
			return fmt.Errorf("class %s declares parameter %q twice", c.name, p.Name)
		case !parameterTypes[p.Type]:
			return fmt.Errorf("class %s, parameter %q: unknown type %q", c.name, p.Name, p.Type)
		case p.Min != nil && p.Max != nil && *p.Min > *p.Max:
			return fmt.Errorf("class %s, parameter %q: its least value is above its most", c.name, p.Name)
		}
		seen[p.Name] = true
	}
	return nil
}

func (c Class) parameterInfos() []*yarfv1.ParameterInfo {
	infos := make([]*yarfv1.ParameterInfo, 0, len(c.parameters))
	for _, p := range c.parameters {
		infos = append(infos, &yarfv1.ParameterInfo{
			Name: p.Name, Type: p.Type, DefaultValue: p.Default, Required: p.Required,
			Min: p.Min, Max: p.Max, Choices: p.Choices, Doc: p.Doc,
		})
	}
	return infos
}
