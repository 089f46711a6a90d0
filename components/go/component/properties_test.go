package component_test

import (
	"errors"
	"math"
	"slices"
	"testing"

	"yarf.dev/components/go/component"
	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

func properties(values map[string]*yarfv1.Property) *component.Properties {
	return component.NewProperties(&yarfv1.Properties{Values: values})
}

func floatValue(f float64) *yarfv1.Property {
	return &yarfv1.Property{Value: &yarfv1.Property_FloatValue{FloatValue: f}}
}

func intValue(i int64) *yarfv1.Property {
	return &yarfv1.Property{Value: &yarfv1.Property_IntValue{IntValue: i}}
}

func stringValue(s string) *yarfv1.Property {
	return &yarfv1.Property{Value: &yarfv1.Property_StringValue{StringValue: s}}
}

func rgbValue(r, g, b float64) *yarfv1.Property {
	return &yarfv1.Property{Value: &yarfv1.Property_RgbValue{RgbValue: &yarfv1.Rgb{R: r, G: g, B: b}}}
}

func TestPropertiesReadValuesAndDefaults(t *testing.T) {
	p := properties(map[string]*yarfv1.Property{
		"radius":   floatValue(2.5),
		"count":    intValue(7),
		"scale":    intValue(3), // an int where a float is read
		"albedo":   rgbValue(0.1, 0.2, 0.3),
		"grey":     floatValue(0.25), // a float where an rgb is read
		"mode":     stringValue("fast"),
		"visible":  {Value: &yarfv1.Property_BoolValue{BoolValue: true}},
		"up":       {Value: &yarfv1.Property_Vec3Value{Vec3Value: &yarfv1.Vec3{Z: 1}}},
		"material": {Value: &yarfv1.Property_Reference{Reference: "red"}},
	})
	if got := p.Float("radius", 1); got != 2.5 {
		t.Errorf("radius %v", got)
	}
	if got := p.Int("count", 1); got != 7 {
		t.Errorf("count %v", got)
	}
	if got := p.Float("scale", 1); got != 3 {
		t.Errorf("scale %v", got)
	}
	if got := p.Color("albedo", [3]float64{}); got != [3]float64{0.1, 0.2, 0.3} {
		t.Errorf("albedo %v", got)
	}
	if got := p.Reflectance("grey", [3]float64{}); got != [3]float64{0.25, 0.25, 0.25} {
		t.Errorf("grey %v", got)
	}
	if got := p.String("mode", ""); got != "fast" {
		t.Errorf("mode %v", got)
	}
	if got := p.Bool("visible", false); !got {
		t.Errorf("visible %v", got)
	}
	if got := p.Vec3("up", [3]float64{}); got != [3]float64{0, 0, 1} {
		t.Errorf("up %v", got)
	}
	if got := p.Reference("material", ""); got != "red" {
		t.Errorf("material %v", got)
	}
	if got := p.Float("absent", 4); got != 4 {
		t.Errorf("absent %v", got)
	}
	if p.Err() != nil || len(p.Unread()) != 0 {
		t.Errorf("err %v, unread %v", p.Err(), p.Unread())
	}
}

func TestPropertiesListUnreadKeys(t *testing.T) {
	p := properties(map[string]*yarfv1.Property{
		"reflectance": floatValue(0.5),
		"relfectance": floatValue(0.5),
		"roughness":   floatValue(0.1),
	})
	p.Reflectance("reflectance", [3]float64{})
	if got, want := p.Unread(), []string{"relfectance", "roughness"}; !slices.Equal(got, want) {
		t.Errorf("unread %v, want %v", got, want)
	}
}

func TestPropertiesReportTheFirstError(t *testing.T) {
	tests := []struct {
		name string
		read func(*component.Properties)
		want string
	}{
		{"wrong type", func(p *component.Properties) { p.Color("s", [3]float64{}) },
			"property 's' must be of type rgb or float, not string"},
		{"int is no rgb", func(p *component.Properties) { p.Color("i", [3]float64{}) },
			"property 'i' must be of type rgb or float, not int"},
		{"float is no int", func(p *component.Properties) { p.Int("f", 0) },
			"property 'f' must be of type int, not float"},
		{"out of range", func(p *component.Properties) { p.Reflectance("bright", [3]float64{}) },
			"property 'bright' must lie in [0, 1] in every channel"},
		{"NaN", func(p *component.Properties) { p.Reflectance("nan", [3]float64{}) },
			"property 'nan' must lie in [0, 1] in every channel"},
		{"missing", func(p *component.Properties) { p.Require("radius") },
			"property 'radius' is missing"},
		{"no value", func(p *component.Properties) { p.Float("empty", 0) },
			"property 'empty' has no value"},
		{"short transform", func(p *component.Properties) { p.Transform("m", [16]float64{}) },
			"property 'm' needs 16 values, got 3"},
		{"first error kept", func(p *component.Properties) {
			p.Int("f", 0)
			p.String("i", "")
		}, "property 'f' must be of type int, not float"},
	}
	for _, test := range tests {
		t.Run(test.name, func(t *testing.T) {
			p := properties(map[string]*yarfv1.Property{
				"s":      stringValue("x"),
				"i":      intValue(1),
				"f":      floatValue(1),
				"bright": rgbValue(0.5, 1.5, 0.5),
				"nan":    floatValue(math.NaN()),
				"empty":  {},
				"m":      {Value: &yarfv1.Property_TransformValue{TransformValue: &yarfv1.Transform{M: []float64{1, 2, 3}}}},
			})
			test.read(p)
			var propertyError *component.PropertyError
			if err := p.Err(); err == nil || err.Error() != test.want || !errors.As(err, &propertyError) {
				t.Errorf("error %v, want %q", err, test.want)
			}
		})
	}
}

func TestPropertiesMistypedValueGivesFallback(t *testing.T) {
	p := properties(map[string]*yarfv1.Property{"n": stringValue("many")})
	if got := p.Int("n", 5); got != 5 {
		t.Errorf("got %v, want the fallback 5", got)
	}
	// A key read with the wrong type was read: only the type error is reported.
	if len(p.Unread()) != 0 {
		t.Errorf("unread %v", p.Unread())
	}
}
