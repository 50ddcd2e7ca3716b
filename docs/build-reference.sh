#!/bin/sh
# Build the authors' program (github.com/AdamBignell/push) as docs/performance.md measured it:
# -O2, the Box2D 2.3.0 of its own tree (not a system Box2D), and no window system. Its Makefile
# uses -O0 and a system Box2D; its GUI needs GLFW. Run headless (-x as the last argument) the
# program never opens a window, so the few GLFW calls of its GUI are linked to stubs that abort.
# Nothing of the program is changed but one missing '#include <limits>', added on the command line.
#
#   git clone https://github.com/AdamBignell/push ~/push
#   docs/build-reference.sh ~/push            # writes ~/push/push-O2
#   phototaxis bench --compare-reference ~/push/push-O2 --rounds 3
#
# Needs g++ and OpenGL's headers and library (Debian: g++ libgl-dev).
set -eu

src=${1:?usage: build-reference.sh PUSH_SOURCE_DIR [OUTPUT]}
out=${2:-$src/push-O2}
box2d=$src/Box2D_v2.3.0/Box2D
[ -d "$box2d/Box2D" ] || { echo "no Box2D_v2.3.0/Box2D/Box2D under $src" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

mkdir -p "$work/GLFW"
cat > "$work/GLFW/glfw3.h" <<'EOF'
/* Just enough of GLFW's interface for the program's GUI code to compile; see glfw_stub.c. */
#include <GL/gl.h>
typedef struct GLFWwindow GLFWwindow;
typedef struct GLFWmonitor GLFWmonitor;
typedef void (*GLFWkeyfun)(GLFWwindow *, int, int, int, int);
typedef void (*GLFWcursorposfun)(GLFWwindow *, double, double);
#define GLFW_PRESS 1
#define GLFW_MOD_SHIFT 0x0001
#define GLFW_KEY_SPACE 32
#define GLFW_KEY_S 83
#define GLFW_KEY_LEFT_BRACKET 91
#define GLFW_KEY_RIGHT_BRACKET 93
#ifdef __cplusplus
extern "C" {
#endif
int glfwInit(void);
void glfwTerminate(void);
GLFWwindow *glfwCreateWindow(int, int, const char *, GLFWmonitor *, GLFWwindow *);
void glfwMakeContextCurrent(GLFWwindow *);
int glfwWindowShouldClose(GLFWwindow *);
void glfwSwapBuffers(GLFWwindow *);
void glfwPollEvents(void);
GLFWkeyfun glfwSetKeyCallback(GLFWwindow *, GLFWkeyfun);
GLFWcursorposfun glfwSetCursorPosCallback(GLFWwindow *, GLFWcursorposfun);
#ifdef __cplusplus
}
#endif
EOF
cat > "$work/glfw_stub.c" <<'EOF'
/* The GUI is never started with -x: reaching any of these is a mistake, said loudly. */
#include <stdio.h>
#include <stdlib.h>
#include "GLFW/glfw3.h"
static void headless(void) { fputs("built headless: run with -x as the last argument\n", stderr); abort(); }
int glfwInit(void) { headless(); return 0; }
void glfwTerminate(void) { headless(); }
GLFWwindow *glfwCreateWindow(int w, int h, const char *t, GLFWmonitor *m, GLFWwindow *s) { headless(); return 0; }
void glfwMakeContextCurrent(GLFWwindow *w) { headless(); }
int glfwWindowShouldClose(GLFWwindow *w) { headless(); return 1; }
void glfwSwapBuffers(GLFWwindow *w) { headless(); }
void glfwPollEvents(void) { headless(); }
GLFWkeyfun glfwSetKeyCallback(GLFWwindow *w, GLFWkeyfun f) { headless(); return 0; }
GLFWcursorposfun glfwSetCursorPosCallback(GLFWwindow *w, GLFWcursorposfun f) { headless(); return 0; }
EOF

cc -O2 -c -I "$work" "$work/glfw_stub.c" -o "$work/glfw_stub.o"
objects=""
for cpp in $(find "$box2d/Box2D/Collision" "$box2d/Box2D/Common" "$box2d/Box2D/Dynamics" "$box2d/Box2D/Rope" -name '*.cpp'); do
    object="$work/$(echo "$cpp" | sed "s|$box2d/||; s|/|_|g; s|\.cpp$|.o|")"
    g++ -std=c++11 -O2 -I "$box2d" -c "$cpp" -o "$object"
    objects="$objects $object"
done
cd "$src"
g++ -std=c++11 -O2 -include limits -I "$box2d" -I "$work" main.cc world.cc robot.cc box.cc guiworld.cc polygon.cc \
    goal.cc $objects "$work/glfw_stub.o" -lGL -lpthread -o "$out"
echo "built $out"
