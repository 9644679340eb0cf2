#version 460
layout(local_size_x = 8) in;
void main() {
    undeclared_thing = 1;
}
